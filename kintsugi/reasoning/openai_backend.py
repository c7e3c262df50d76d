"""Reasoner backed by any OpenAI-compatible chat-completions endpoint, for every registered role.

Works with OpenAI, vLLM, Ollama and llama.cpp server: the role's system prompt
is the system message, the role's prompt plus the request (images as PNG data
URLs) the user message; replies are constrained by the reply type's JSON schema,
or arrive as function calls when the role routes them so (a peg recovery plan:
one tool per skill). Servers that refuse or ignore those strict options get the
same requests in text mode (see `structured.py`). Transport retries with backoff
(timeouts, 429, 5xx) happen only where a retry can help (`transport.py`: a refusal
is never retried); on top of that a reply that does not parse, validate or pass
the role's checks is sent back to the model once with the error quoted.

Images are sent at most `Role.image_max_px` on their longer side (the model is told
the scale); with `reasoner.options.images=measurements` none are sent: the model
works from the checks and measurements the request also carries, and each call's
record counts the images withheld. `preflight` (`preflight.py`) asks the endpoint
what it can do before a campaign's first trial.
"""

from __future__ import annotations

import base64
import json
import os
from dataclasses import dataclass, replace
from typing import Any
from urllib.parse import urlparse

from openai import OpenAI
from pydantic import BaseModel

from kintsugi.core.errors import ConfigError
from kintsugi.reasoning.base import CallStats, Check, redact
from kintsugi.reasoning.images import fit_png
from kintsugi.reasoning.endpoint_options import OpenAIOptions
from kintsugi.reasoning.jsontext import BadReply  # noqa: F401 - re-exported
from kintsugi.reasoning.roles import Role
from kintsugi.reasoning.structured import (  # noqa: F401 - EndpointError, strict_schema, MAX_ATTEMPTS re-exported
    MAX_ATTEMPTS,
    EndpointError,
    StructuredClient,
    StructuredOutput,
    format_instructions,
    strict_schema,
)

OPENAI_HOST = "api.openai.com"
DEFAULT_OPENAI_MODEL = "gpt-4o"
"""The model the paper used; only a default when talking to OpenAI itself."""
PLACEHOLDER_KEY = "sk-local-no-key"
"""Local servers ignore the key, but the SDK insists on one."""


@dataclass(frozen=True)
class Outgoing:
    """One call's first request as it goes out: messages (images as data URLs), the strict options sent
    with them, the text of its parts by name, and the image URLs."""

    role: str
    messages: list[dict[str, Any]]
    options: dict[str, Any]
    parts: dict[str, str]
    images: list[str]


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


class OpenAIReasoner:
    """Any role by chat completions; `last_stats` holds the last call's cost."""

    name = "openai"

    def __init__(self, *, model: str | None = None, base_url: str | None = None,
                 api_key_env: str = "OPENAI_API_KEY", timeout_s: float = 60.0, max_retries: int = 3,
                 structured_output: StructuredOutput = "auto", client: OpenAI | None = None,
                 options: OpenAIOptions | None = None) -> None:
        if model is None and not _is_openai(base_url):
            raise ConfigError(
                f"reasoner.model is not set; set it to the model name your server at {base_url} serves"
            )
        self.model = model or DEFAULT_OPENAI_MODEL
        self.base_url = base_url
        self.timeout_s = timeout_s
        self.options = options or OpenAIOptions()
        self.client = client or OpenAI(
            base_url=base_url,
            api_key=resolve_api_key(api_key_env, base_url),
            timeout=timeout_s,
            max_retries=0,  # `transport.send` retries, and only what a retry can fix
        )
        self.structured = StructuredClient(self.client, self.model, where=base_url or "https://api.openai.com/v1",
                                           timeout_s=timeout_s, structured_output=structured_output,
                                           max_retries=max_retries, max_reply_tokens=self.options.max_reply_tokens)
        self._images = (0, 0)
        if self.options.learnt is not None:
            self.structured.learnt(dict(self.options.learnt.text_mode))

    @property
    def sees_images(self) -> bool:
        """False with `images=measurements`: methods then leave optional camera images out of requests."""
        return self.options.images == "send"

    @property
    def last_stats(self) -> CallStats | None:
        return self.structured.last_stats

    @last_stats.setter
    def last_stats(self, value: CallStats | None) -> None:
        self.structured.last_stats = value

    def preflight(self, roles: dict[str, list[Role]], trials: dict[str, Any] | None = None) -> Any:
        """Ask the endpoint once what it can do for these roles (by method; `trials`: each method's first trial,
        whose first requests are counted); raises CapabilityError with one line when it cannot serve them, else
        returns the `Findings` (notes, and what the trials are told)."""
        from kintsugi.reasoning.preflight import check_endpoint

        return check_endpoint(self, roles, trials)

    def answer(self, role: Role, request: BaseModel, check: Check | None = None) -> BaseModel:
        """The role's system prompt as the system message, its prompt plus the request (images attached) as
        the user message -> a validated, checked reply (strict or text output and one repair round come from
        `structured`)."""
        messages = self.messages(role, request)
        tools = role.tools(request) if role.tools is not None else None
        sent, withheld = self._images
        try:
            return self.structured.ask(role.name, messages, role.reply, check=check, tools=tools,
                                       prompt=role.prompt_path)
        finally:
            if self.structured.last_stats is not None:
                self.structured.last_stats = replace(self.structured.last_stats, images_sent=sent,
                                                     images_withheld=withheld)

    def messages(self, role: Role, request: BaseModel) -> list[dict[str, Any]]:
        """The system and user messages of a call (images fitted to the size sent)."""
        return [{"role": "system", "content": role.system_text()},
                {"role": "user", "content": self._user_content(role, request)}]

    def outgoing(self, role: Role, request: BaseModel) -> Outgoing:
        """Exactly what the first attempt of `answer(role, request)` sends, and its parts by name (what the
        preflight counts)."""
        messages = self.messages(role, request)
        tools = role.tools(request) if role.tools is not None else None
        sent, options = self.structured.first_attempt(messages, role.reply, tools)
        user = messages[1]["content"]
        text = user if isinstance(user, str) else user[0]["text"]
        prompt = role.prompt_text()
        parts = {"system prompt": role.system_text(), "role prompt": prompt,
                 "request data": text[len(prompt):] if text.startswith(prompt) else text}
        if "tools" in options:
            parts["tool definitions"] = json.dumps(options["tools"])
        if not options:
            parts["answer format"] = format_instructions(role.reply, tools)
        images = [p for p in user if p.get("type") == "image_url"] if isinstance(user, list) else []
        return Outgoing(role.name, sent, options, parts, [p["image_url"]["url"] for p in images])

    # --- internals ---------------------------------------------------------
    def _user_content(self, role: Role, request: BaseModel) -> str | list[dict[str, Any]]:
        images: list[tuple[str, bytes]] = []
        withheld: list[str] = []
        send = self.options.images == "send"

        def on_bytes(path: tuple[str, ...], data: bytes) -> str:
            if not send:
                withheld.append(".".join(path))
                return "<image withheld: this endpoint gets measurements only; use the checks and measurements>"
            images.append((".".join(path), data))
            return f"<image {len(images)}, attached below>"

        payload = redact(request, on_bytes)
        self._images = (len(images), len(withheld))
        sections = role.sections(request) if role.sections is not None else ""
        text = f"{role.prompt_text()}\n\n{sections}# Request\n```json\n{json.dumps(payload, indent=2)}\n```"
        if not images:
            return text
        parts: list[dict[str, Any]] = [{"type": "text", "text": text}]
        limit = min(role.image_max_px, self.options.image_max_px or role.image_max_px)
        for i, (path, data) in enumerate(images, 1):
            png, note = fit_png(data, limit)
            label = f"Image {i} ({path}): {role.image_labels.get(path, path)}" + (f" ({note})" if note else "")
            parts.append({"type": "text", "text": label})
            url = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
            parts.append({"type": "image_url", "image_url": {"url": url}})
        return parts


def make_openai_reasoner(settings: Any, options: OpenAIOptions | None = None) -> OpenAIReasoner:
    """Registry factory: the common ReasonerSettings fields and the backend's options -> OpenAIReasoner."""
    return OpenAIReasoner(
        model=settings.model,
        base_url=settings.base_url,
        api_key_env=settings.api_key_env,
        timeout_s=settings.timeout_s,
        max_retries=settings.max_retries,
        structured_output=settings.structured_output,
        options=options if isinstance(options, OpenAIOptions) else None,
    )
