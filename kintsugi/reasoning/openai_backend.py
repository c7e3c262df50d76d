"""Reasoner backed by any OpenAI-compatible chat-completions endpoint.

Works with OpenAI, vLLM, Ollama and llama.cpp server: images go as PNG data
URLs, judge/analyze replies are constrained by a JSON schema, plans come back as
function calls (one tool per recovery skill). Transport retries with backoff
(429, 5xx, timeouts) are the SDK's own; on top of that a reply that does not
parse or validate is sent back to the model once with the error quoted.
"""

from __future__ import annotations

import base64
import json
import os
import re
from functools import lru_cache
from importlib import resources
from typing import Any, Callable, TypeVar
from urllib.parse import urlparse

import openai
from openai import OpenAI
from pydantic import BaseModel, ValidationError

from kintsugi.errors import ConfigError, ReasoningError
from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.base import CallStats, redact
from kintsugi.reasoning.types import (
    AnalyzeReply,
    AnalyzeRequest,
    JudgeReply,
    JudgeRequest,
    PlanReply,
    PlanRequest,
    Role,
)
from kintsugi.reasoning.validation import describe_validation_error, validate_analysis, validate_plan

OPENAI_HOST = "api.openai.com"
DEFAULT_OPENAI_MODEL = "gpt-4o"
"""The model the paper used; only a default when talking to OpenAI itself."""
PLACEHOLDER_KEY = "sk-local-no-key"
"""Local servers ignore the key, but the SDK insists on one."""
MAX_ATTEMPTS = 2
"""First reply plus one repair round; more rarely helps and doubles latency."""

IMAGE_LABELS = {
    "outcome.image_png": "terminal camera image at the end of the skill",
    "goal_image_png": "goal image: this skill's terminal image in the default condition (what success looks like)",
}

M = TypeVar("M", bound=BaseModel)


class EndpointError(ReasoningError):
    """The endpoint could not be used (unreachable, timeout, HTTP error) after the SDK's retries."""


class BadReply(ReasoningError):
    """One reply could not be used; its message is quoted back to the model for repair."""


@lru_cache(maxsize=None)
def load_prompt(name: str) -> str:
    """Text of prompts/<name>.md, shipped as package data so users can read and edit it."""
    return resources.files("kintsugi.reasoning").joinpath("prompts", f"{name}.md").read_text(encoding="utf-8")


def _is_openai(base_url: str | None) -> bool:
    return base_url is None or (urlparse(base_url).hostname or "").endswith(OPENAI_HOST)


def resolve_api_key(api_key_env: str, base_url: str | None) -> str:
    """Key from the named env var; local servers get a placeholder when it is unset."""
    key = os.environ.get(api_key_env, "").strip()
    if key:
        return key
    if _is_openai(base_url):
        raise ConfigError(
            f"the openai reasoner needs an API key: export {api_key_env}=<your key>, or point --base-url "
            f"(reasoner.base_url) at a local OpenAI-compatible server (vLLM, Ollama, llama.cpp)"
        )
    return PLACEHOLDER_KEY


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


def _response_format(model: type[BaseModel]) -> dict[str, Any]:
    return {
        "type": "json_schema",
        "json_schema": {"name": model.__name__, "schema": strict_schema(model), "strict": True},
    }


def _plan_tools(request: PlanRequest) -> list[dict[str, Any]]:
    """One function per recovery skill; its parameters are the skill's axes as absolute goals."""
    tools = []
    for skill, axes in request.skills.items():
        current = request.goals.get(skill)
        props = {}
        for axis in axes:
            unit = "degrees" if axis == "roll" else "mm"
            now = f"; current goal {getattr(current, axis):g}" if current is not None else ""
            props[axis] = {"type": "number", "description": f"absolute goal {axis} in {unit}{now}"}
        tools.append(
            {
                "type": "function",
                "function": {
                    "name": skill,
                    "description": f"Execute the {skill} skill with an absolute goal for {', '.join(axes)}. "
                    f"Each value may differ from the current goal by at most {request.max_step_mm:g}.",
                    "parameters": {
                        "type": "object",
                        "properties": props,
                        "required": list(axes),
                        "additionalProperties": False,
                    },
                    "strict": True,
                },
            }
        )
    return tools


def _content_json(message: Any) -> Any:
    """JSON object from an assistant message's text (refusals are reported as such)."""
    refusal = getattr(message, "refusal", None)
    if refusal and not message.content:
        raise BadReply(f"the model refused ({refusal}); this is a robot-control task, answer in the requested format")
    return _decode_json(message.content)


def _decode_json(text: str | None) -> Any:
    """JSON from a reply, tolerating code fences and prose around one object."""
    if text is None or not text.strip():
        raise BadReply("the reply was empty; answer with one JSON object")
    stripped = re.sub(r"^\s*```(?:json)?\s*|\s*```\s*$", "", text.strip())
    try:
        return json.loads(stripped)
    except (json.JSONDecodeError, RecursionError) as first:
        start, end = stripped.find("{"), stripped.rfind("}")
        if 0 <= start < end:
            try:
                return json.loads(stripped[start : end + 1])
            except (json.JSONDecodeError, RecursionError):
                pass
        raise BadReply(f"the reply is not valid JSON ({first}); answer with one JSON object and nothing else") from None


def _validate(model: type[M], data: Any) -> M:
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise BadReply(f"the reply does not match the schema: {describe_validation_error(exc)}") from None


class OpenAIReasoner:
    """Judge, analyze and plan by chat completions; `last_stats` holds the last call's cost."""

    name = "openai"

    def __init__(self, *, model: str | None = None, base_url: str | None = None,
                 api_key_env: str = "OPENAI_API_KEY", timeout_s: float = 60.0, max_retries: int = 3,
                 client: OpenAI | None = None) -> None:
        if model is None and not _is_openai(base_url):
            raise ConfigError(
                f"reasoner.model is not set; set it to the model name your server at {base_url} serves"
            )
        self.model = model or DEFAULT_OPENAI_MODEL
        self.base_url = base_url
        self.timeout_s = timeout_s
        self.client = client or OpenAI(
            base_url=base_url,
            api_key=resolve_api_key(api_key_env, base_url),
            timeout=timeout_s,
            max_retries=max_retries,
        )
        self.last_stats: CallStats | None = None

    # --- roles -------------------------------------------------------------
    def judge(self, request: JudgeRequest) -> JudgeReply:
        return self._run(
            "judge", request, {"response_format": _response_format(JudgeReply)},
            lambda msg: _validate(JudgeReply, _content_json(msg)),
        )

    def analyze(self, request: AnalyzeRequest) -> AnalyzeReply:
        return self._run(
            "analyze", request, {"response_format": _response_format(AnalyzeReply)},
            lambda msg: validate_analysis(_validate(AnalyzeReply, _content_json(msg)), request),
        )

    def plan(self, request: PlanRequest) -> PlanReply:
        """Unclamped plan from the model's tool calls; the caller clamps with validate_plan."""

        def parse(msg: Any) -> PlanReply:
            if msg.tool_calls:
                reply = self._plan_from_tool_calls(msg.tool_calls, request)
            else:
                reply = _validate(PlanReply, _content_json(msg))
            validate_plan(reply, request)  # structural errors go back to the model; clamping is the caller's
            return reply

        return self._run("plan", request, {"tools": _plan_tools(request), "tool_choice": "required"}, parse)

    # --- internals ---------------------------------------------------------
    @staticmethod
    def _plan_from_tool_calls(calls: list[Any], request: PlanRequest) -> PlanReply:
        steps = []
        for call in calls:
            fn = getattr(call, "function", None)
            if fn is None:
                raise BadReply("only function tool calls are allowed")
            if fn.name not in request.skills:
                raise BadReply(f"unknown tool {fn.name!r}; the only tools are {', '.join(request.skills)}")
            try:
                args = json.loads(fn.arguments or "{}")
            except (json.JSONDecodeError, RecursionError) as exc:
                raise BadReply(f"arguments of {fn.name} are not valid JSON ({exc})") from None
            if not isinstance(args, dict):
                raise BadReply(f"arguments of {fn.name} must be an object like {{\"y\": 12.5}}")
            steps.append({"skill": fn.name, "goal": args})
        return _validate(PlanReply, {"steps": steps})

    def _user_content(self, role: Role, request: BaseModel) -> str | list[dict[str, Any]]:
        images: list[tuple[str, bytes]] = []

        def on_bytes(path: tuple[str, ...], data: bytes) -> str:
            images.append((".".join(path), data))
            return f"<image {len(images)}, attached below>"

        payload = redact(request, on_bytes)
        text = f"{load_prompt(role)}\n\n# Request\n```json\n{json.dumps(payload, indent=2)}\n```"
        if not images:
            return text
        parts: list[dict[str, Any]] = [{"type": "text", "text": text}]
        for i, (path, data) in enumerate(images, 1):
            parts.append({"type": "text", "text": f"Image {i} ({path}): {IMAGE_LABELS.get(path, path)}"})
            url = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
            parts.append({"type": "image_url", "image_url": {"url": url}})
        return parts

    def _complete(self, messages: list[dict[str, Any]], extra: dict[str, Any]) -> Any:
        where = self.base_url or "https://api.openai.com/v1"
        try:
            return self.client.chat.completions.create(model=self.model, messages=messages, **extra)
        except openai.APITimeoutError:
            raise EndpointError(
                f"no reply from {where} within {self.timeout_s:g} s (after the SDK's retries); "
                f"raise reasoner.timeout_s or check that the server is not overloaded"
            ) from None
        except openai.APIConnectionError as exc:
            raise EndpointError(f"cannot reach {where} ({exc}); is the server running and the URL right?") from None
        except openai.AuthenticationError:
            raise EndpointError(f"{where} rejected the API key; check the env var named by reasoner.api_key_env") from None
        except openai.NotFoundError as exc:
            raise EndpointError(f"{where} does not know model {self.model!r} ({exc.message}); set reasoner.model") from None
        except openai.APIStatusError as exc:
            raise EndpointError(
                f"{where} answered HTTP {exc.status_code}: {exc.message}; if this is 400, the model may not "
                f"support images, JSON-schema output or tool calls"
            ) from None
        except openai.APIError as exc:
            raise EndpointError(f"{where} returned an unusable response: {exc}") from None

    def _run(self, role: Role, request: BaseModel, extra: dict[str, Any], parse: Callable[[Any], M]) -> M:
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": load_prompt("system")},
            {"role": "user", "content": self._user_content(role, request)},
        ]
        tokens_in = tokens_out = 0
        problem = ""
        for attempt in range(1, MAX_ATTEMPTS + 1):
            self.last_stats = CallStats(tokens_in, tokens_out, attempt)
            completion = self._complete(messages, extra)
            usage = getattr(completion, "usage", None)
            if usage is not None:
                tokens_in += usage.prompt_tokens or 0
                tokens_out += usage.completion_tokens or 0
            self.last_stats = CallStats(tokens_in, tokens_out, attempt)
            if not completion.choices:
                problem = "the response had no choices"
                continue
            message = completion.choices[0].message
            try:
                return parse(message)
            except ReasoningError as exc:
                problem = str(exc)
                messages.extend(_repair_messages(message, problem))
        raise ReasoningError(
            f"{role}: model {self.model!r} gave no usable reply in {MAX_ATTEMPTS} attempts; last problem: {problem}. "
            f"Try a stronger model or check the prompt in kintsugi/reasoning/prompts/{role}.md"
        )


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
            {"role": "tool", "tool_call_id": c["id"], "content": "Not executed: the plan was rejected."}
            for c in assistant["tool_calls"]
        ]
    out.append(
        {
            "role": "user",
            "content": f"Your reply was rejected: {problem}\nAnswer again in the requested format, fixing this.",
        }
    )
    return out


@REASONERS.register(
    "openai",
    "any OpenAI-compatible chat-completions endpoint (OpenAI, vLLM, Ollama, llama.cpp): "
    "set reasoner.model, reasoner.base_url, and the key in $OPENAI_API_KEY (or reasoner.api_key_env)",
    tags=("network", "vlm"),
)
def make_openai_reasoner(settings: Any) -> OpenAIReasoner:
    """Registry factory: ReasonerSettings -> OpenAIReasoner."""
    return OpenAIReasoner(
        model=settings.model,
        base_url=settings.base_url,
        api_key_env=settings.api_key_env,
        timeout_s=settings.timeout_s,
        max_retries=settings.max_retries,
    )
