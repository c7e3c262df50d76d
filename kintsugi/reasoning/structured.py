"""Typed replies from any OpenAI-compatible endpoint, in strict or plain-text mode.

`StructuredClient.ask(role, messages, Reply)` returns a validated `Reply` (any
pydantic model), so every role shares one transport. Two modes:

- **strict**: the server enforces the format: `response_format` with the reply's
  JSON schema (strict), or, for replies that arrive as function calls, `tools`
  with `tool_choice="required"`.
- **text**: none of those options are sent; the schema (and the tools, written
  as JSON) is described in the prompt and the reply is parsed tolerantly.

`auto` starts strict and moves an option to text for the rest of the client's
life when the server refuses it (an HTTP error naming it, whatever the status) or ignores it (a reply
that is not a bare JSON object, or has no tool call). Both modes share the same
pydantic validation, the caller's check and one repair round; each call's
`CallStats` says which mode it used and why it switched.
"""

from __future__ import annotations

import json
from typing import Any, Callable, Literal, TypeVar, get_args

from openai import OpenAI
from pydantic import BaseModel, ValidationError

from kintsugi.core.errors import ConfigError, ReasoningError
from kintsugi.reasoning.base import CallStats
from kintsugi.reasoning.jsontext import BadReply, describe_validation_error, extract_json_object, loads_object
from kintsugi.reasoning.roles import ToolRoute  # noqa: F401 - re-exported
from kintsugi.reasoning.transport import (  # noqa: F401 - errors re-exported
    STRICT_OPTION_WORDS,
    ContextTooLong,
    EndpointError,
    ImagesRefused,
    Refused,
    send,
)

StructuredOutput = Literal["auto", "strict", "text"]
Mode = Literal["strict", "text"]
Option = Literal["json_schema", "tools"]
"""The two strict options a server may refuse, remembered separately."""

MAX_ATTEMPTS = 2
"""First reply plus one repair round; more rarely helps and doubles latency."""

M = TypeVar("M", bound=BaseModel)


def strict_schema(model: type[BaseModel]) -> dict[str, Any]:
    """`model.model_json_schema()` made acceptable to OpenAI's strict structured outputs.

    Strict mode wants every property required, additionalProperties false, no
    defaults and no string-length keywords; pydantic still enforces those limits
    when the reply is parsed.
    """

    def fix(node: Any) -> Any:
        if isinstance(node, dict):
            out = {k: fix(v) for k, v in node.items() if k not in ("default", "maxLength", "minLength")}
            if "properties" in out:
                out["required"] = list(out["properties"])
                out["additionalProperties"] = False
            return out
        if isinstance(node, list):
            return [fix(v) for v in node]
        return node

    return fix(model.model_json_schema())


def response_format(model: type[BaseModel]) -> dict[str, Any]:
    return {
        "type": "json_schema",
        "json_schema": {"name": model.__name__, "schema": strict_schema(model), "strict": True},
    }


def describe_tools(tools: list[dict[str, Any]]) -> str:
    """The functions as text, one line each, for a model that cannot be sent `tools`."""
    lines = []
    for tool in tools:
        fn = tool["function"]
        props = fn.get("parameters", {}).get("properties", {})
        args = ", ".join(f"{name}: {spec.get('description', spec.get('type', ''))}" for name, spec in props.items())
        lines.append(f"- {fn['name']}({args}): {fn.get('description', '')}")
    return "\n".join(lines)


def format_instructions(reply: type[BaseModel], tools: ToolRoute | None = None) -> str:
    """What text mode adds to the prompt: the reply's JSON schema (and the tools as JSON)."""
    schema = json.dumps(reply.model_json_schema(), separators=(", ", ": "))
    text = ("# Answer format\nAnswer with one JSON object and nothing else (no prose, no code fences). "
            f"It must match this JSON schema:\n{schema}")
    if tools is not None:
        text += f"\nDo not call functions. {tools.text_hint}\nThe functions:\n{describe_tools(tools.tools)}"
    return text


def with_instructions(messages: list[dict[str, Any]], text: str) -> list[dict[str, Any]]:
    """A copy of `messages` with `text` appended to the last user message (images stay where they are)."""
    out = [dict(m) for m in messages]
    for m in reversed(out):
        if m["role"] == "user":
            content = m["content"]
            m["content"] = (f"{content}\n\n{text}" if isinstance(content, str)
                            else [*content, {"type": "text", "text": text}])
            return out
    return [*out, {"role": "user", "content": text}]


class StructuredClient:
    """One chat-completions transport for every role; remembers which strict options the server refused."""

    def __init__(self, client: OpenAI, model: str, *, where: str, timeout_s: float,
                 structured_output: StructuredOutput = "auto", max_retries: int = 0,
                 max_reply_tokens: int | None = None) -> None:
        if structured_output not in get_args(StructuredOutput):
            raise ConfigError(f"reasoner.structured_output is {structured_output!r}; use one of "
                              f"{', '.join(get_args(StructuredOutput))}")
        self.client = client
        self.model = model
        self.where = where
        self.timeout_s = timeout_s
        self.max_retries = max_retries
        self.max_reply_tokens = max_reply_tokens
        self.structured_output: StructuredOutput = structured_output
        self.text_only: dict[Option, str] = {}
        """Options moved to text mode (auto), with the reason; kept for the client's life."""
        self.preset: dict[Option, str] = {}
        """Options in text mode from the start: the campaign's preflight found the server refuses them."""
        self.last_stats: CallStats | None = None

    def mode_for(self, option: Option) -> Mode:
        return "text" if self.structured_output == "text" or option in self.text_only else "strict"

    def ask(self, role: str, messages: list[dict[str, Any]], reply: type[M], *,
            check: Callable[[M], M] | None = None, tools: ToolRoute | None = None, prompt: str | None = None) -> M:
        """Messages -> a validated `reply`; `check` may raise ReasoningError to ask for one repair.

        `prompt` is where the role's prompt file lives, named in the error when no reply is usable.

        With `tools`, strict mode asks for function calls and builds the reply
        with `tools.to_data`; text mode asks for the reply's JSON directly.
        """
        option: Option = "tools" if tools is not None else "json_schema"
        fmt = format_instructions(reply, tools)
        mode = self.mode_for(option)
        msgs = with_instructions(messages, fmt) if mode == "text" else [dict(m) for m in messages]
        tokens_in = tokens_out = 0
        note: str | None = self._preset_note(option) if mode == "text" else None
        problem = ""

        def stats(attempt: int) -> CallStats:
            self.last_stats = CallStats(tokens_in, tokens_out, attempt, mode, note)
            return self.last_stats

        for attempt in range(1, MAX_ATTEMPTS + 1):
            stats(attempt)
            try:
                completion = self._complete(msgs, self._options(mode, reply, tools), role)
            except Refused as refused:
                if self.structured_output == "strict":
                    raise EndpointError(
                        f"{self.where} refused strict structured output for {role} ({refused.reason}); use "
                        f"--structured-output auto or text (reasoner.structured_output) to ask for JSON in plain text"
                    ) from None
                note = self._to_text(option, f"server refused it: {refused.reason}")
                mode = "text"
                msgs = with_instructions(msgs, fmt)
                stats(attempt)
                completion = self._complete(msgs, {}, role)
            usage = getattr(completion, "usage", None)
            if usage is not None:
                tokens_in += usage.prompt_tokens or 0
                tokens_out += usage.completion_tokens or 0
            stats(attempt)
            if not completion.choices:
                problem = "the response had no choices"
                continue
            choice = completion.choices[0]
            message = choice.message
            switch = False
            if mode == "strict" and self.structured_output == "auto":
                ignored = _ignored(message, getattr(choice, "finish_reason", None), option)
                if ignored:
                    note = self._to_text(option, f"server ignored it: {ignored}")
                    switch = True
                    stats(attempt)
            try:
                return self._parse(message, reply, check, tools)
            except ReasoningError as exc:
                problem = str(exc)
                msgs.extend(_repair_messages(message, problem))
                if switch:
                    mode = "text"
                    msgs = with_instructions(msgs, fmt)
        raise ReasoningError(
            f"{role}: model {self.model!r} gave no usable reply in {MAX_ATTEMPTS} attempts; last problem: {problem}. "
            + (f"Try a stronger model or check the prompt in {prompt}" if prompt else "Try a stronger model")
        )

    def first_attempt(self, messages: list[dict[str, Any]], reply: type[BaseModel],
                      tools: ToolRoute | None = None) -> tuple[list[dict[str, Any]], dict[str, Any]]:
        """(messages, options) of the first request `ask` sends for these messages, in the mode in effect."""
        option: Option = "tools" if tools is not None else "json_schema"
        mode = self.mode_for(option)
        if mode == "text":
            return with_instructions(messages, format_instructions(reply, tools)), {}
        return [dict(m) for m in messages], self._options(mode, reply, tools)

    def learnt(self, text_only: dict[Option, str]) -> None:
        """Start with these options in text mode (what a campaign's preflight learnt about the server)."""
        for option, why in text_only.items():
            self.text_only[option] = why
            self.preset[option] = why

    # --- internals ---------------------------------------------------------
    def _preset_note(self, option: Option) -> str | None:
        if self.structured_output == "text" or option not in self.preset:
            return None
        what = "tool_choice=\"required\"" if option == "tools" else "response_format json_schema"
        return f"{what}: text mode from the preflight ({self.preset[option]})"

    def _to_text(self, option: Option, why: str) -> str:
        self.text_only[option] = why
        what = "tool_choice=\"required\"" if option == "tools" else "response_format json_schema"
        return f"{what}: {why}; switched to text mode for the rest of this reasoner's life"

    @staticmethod
    def _options(mode: Mode, reply: type[BaseModel], tools: ToolRoute | None) -> dict[str, Any]:
        if mode == "text":
            return {}
        if tools is not None:
            return {"tools": tools.tools, "tool_choice": "required"}
        return {"response_format": response_format(reply)}

    @staticmethod
    def _parse(message: Any, reply: type[M], check: Callable[[M], M] | None, tools: ToolRoute | None) -> M:
        calls = getattr(message, "tool_calls", None) or []
        if tools is not None and calls:
            data = tools.to_data(_decode_calls(calls, tools))
        else:
            refusal = getattr(message, "refusal", None)
            if refusal and not message.content:
                raise BadReply(f"the model refused ({refusal}); this is a robot-control task, "
                               f"answer in the requested format")
            data = extract_json_object(message.content)
        try:
            value = reply.model_validate(data)
        except ValidationError as exc:
            raise BadReply(f"the reply does not match the schema: {describe_validation_error(exc)}") from None
        return check(value) if check is not None else value

    def _complete(self, messages: list[dict[str, Any]], options: dict[str, Any], role: str = "this role") -> Any:
        if self.max_reply_tokens is not None:
            options = {**options, "max_tokens": self.max_reply_tokens}
        return send(self.client, self.model, messages, options, where=self.where, timeout_s=self.timeout_s,
                    max_retries=self.max_retries, what=f"the {role} request")


def _ignored(message: Any, finish_reason: str | None, option: Option) -> str | None:
    """Why a strict-mode reply shows the server ignored the option, or None if it complied."""
    if getattr(message, "refusal", None) or finish_reason == "length":
        return None  # a truncated reply is the token limit's fault, not the server's
    if option == "tools":
        return None if getattr(message, "tool_calls", None) else 'the reply had no tool call despite tool_choice="required"'
    if loads_object(message.content or "") is not None:
        return None
    return "the reply was not a bare JSON object despite response_format json_schema"


def _decode_calls(calls: list[Any], tools: ToolRoute) -> list[tuple[str, dict[str, Any]]]:
    out = []
    for call in calls:
        fn = getattr(call, "function", None)
        if fn is None:
            raise BadReply("only function tool calls are allowed")
        if fn.name not in tools.names:
            raise BadReply(f"unknown tool {fn.name!r}; the only tools are {', '.join(tools.names)}")
        try:
            args = json.loads(fn.arguments or "{}")
        except (ValueError, RecursionError) as exc:
            raise BadReply(f"arguments of {fn.name} are not valid JSON ({exc})") from None
        if not isinstance(args, dict):
            raise BadReply(f"arguments of {fn.name} must be one JSON object of named arguments")
        out.append((fn.name, args))
    return out


def _repair_messages(message: Any, problem: str) -> list[dict[str, Any]]:
    """The rejected assistant turn (and tool results if it called tools), then the error to fix."""
    assistant: dict[str, Any] = {"role": "assistant", "content": message.content or ""}
    out: list[dict[str, Any]] = [assistant]
    calls = getattr(message, "tool_calls", None) or []
    if calls:
        assistant["tool_calls"] = [
            {"id": c.id, "type": "function", "function": {"name": c.function.name, "arguments": c.function.arguments}}
            for c in calls
            if getattr(c, "function", None) is not None
        ]
        out += [
            {"role": "tool", "tool_call_id": c["id"], "content": "Not executed: the reply was rejected."}
            for c in assistant["tool_calls"]
        ]
    out.append(
        {
            "role": "user",
            "content": f"Your reply was rejected: {problem}\nAnswer again in the requested format, fixing this.",
        }
    )
    return out
