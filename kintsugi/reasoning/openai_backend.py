"""Reasoner backed by any OpenAI-compatible chat-completions endpoint.

Works with OpenAI, vLLM, Ollama and llama.cpp server: images go as PNG data
URLs, judge/analyze replies are constrained by a JSON schema, plans come back as
function calls (one tool per recovery skill). Servers that refuse or ignore
those strict options get the same requests in text mode (see `structured.py`).
Transport retries with backoff (429, 5xx, timeouts) are the SDK's own; on top of
that a reply that does not parse or validate is sent back to the model once with
the error quoted. New roles reuse it all through `OpenAIReasoner.ask`.
"""

from __future__ import annotations

import base64
import json
import os
from functools import lru_cache
from importlib import resources
from typing import Any, Callable, TypeVar
from urllib.parse import urlparse

from openai import OpenAI
from pydantic import BaseModel

from kintsugi.core.errors import ConfigError
from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.base import CallStats, redact
from kintsugi.reasoning.jsontext import BadReply  # noqa: F401 - re-exported
from kintsugi.reasoning.prompting import robot_section
from kintsugi.reasoning.structured import (  # noqa: F401 - EndpointError, strict_schema, MAX_ATTEMPTS re-exported
    MAX_ATTEMPTS,
    EndpointError,
    StructuredClient,
    StructuredOutput,
    ToolRoute,
    strict_schema,
)
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    JudgeReply,
    JudgeRequest,
    PlanReply,
    PlanRequest,
)
from kintsugi.methods.recovery.validation import validate_analysis, validate_plan

OPENAI_HOST = "api.openai.com"
DEFAULT_OPENAI_MODEL = "gpt-4o"
"""The model the paper used; only a default when talking to OpenAI itself."""
PLACEHOLDER_KEY = "sk-local-no-key"
"""Local servers ignore the key, but the SDK insists on one."""
PLAN_TEXT_HINT = ('Write each function call as one step {"skill": <function name>, "goal": {<its arguments>}}, '
                  'in execution order, inside {"steps": [...]}.')

IMAGE_LABELS = {
    "outcome.image_png": "terminal camera image at the end of the skill",
    "goal_image_png": "goal image: this skill's terminal image in the default condition (what success looks like)",
}

M = TypeVar("M", bound=BaseModel)


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


class OpenAIReasoner:
    """Judge, analyze and plan by chat completions; `last_stats` holds the last call's cost."""

    name = "openai"

    def __init__(self, *, model: str | None = None, base_url: str | None = None,
                 api_key_env: str = "OPENAI_API_KEY", timeout_s: float = 60.0, max_retries: int = 3,
                 structured_output: StructuredOutput = "auto", client: OpenAI | None = None) -> None:
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
        self.structured = StructuredClient(self.client, self.model, where=base_url or "https://api.openai.com/v1",
                                           timeout_s=timeout_s, structured_output=structured_output)

    @property
    def last_stats(self) -> CallStats | None:
        return self.structured.last_stats

    @last_stats.setter
    def last_stats(self, value: CallStats | None) -> None:
        self.structured.last_stats = value

    # --- roles -------------------------------------------------------------
    def judge(self, request: JudgeRequest) -> JudgeReply:
        return self.ask("judge", request, JudgeReply)

    def analyze(self, request: AnalyzeRequest) -> AnalyzeReply:
        return self.ask("analyze", request, AnalyzeReply, check=lambda reply: validate_analysis(reply, request))

    def plan(self, request: PlanRequest) -> PlanReply:
        """Unclamped plan from the model's tool calls (or JSON steps); the caller clamps with validate_plan."""

        def check(reply: PlanReply) -> PlanReply:
            validate_plan(reply, request)  # structural errors go back to the model; clamping is the caller's
            return reply

        route = ToolRoute(tools=_plan_tools(request), text_hint=PLAN_TEXT_HINT,
                          to_data=lambda calls: {"steps": [{"skill": name, "goal": args} for name, args in calls]})
        return self.ask("plan", request, PlanReply, check=check, tools=route)

    def ask(self, role: str, request: BaseModel, reply: type[M], *, check: Callable[[M], M] | None = None,
            tools: ToolRoute | None = None, system: str = "system") -> M:
        """Any role: prompts/<system>.md as the system message, prompts/<role>.md plus the request (images
        attached) as the user message -> a validated `reply`.

        A new role needs only its request/reply types and prompt files; strict
        or text output, the repair round and accounting come from `structured`.
        """
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": load_prompt(system)},
            {"role": "user", "content": self._user_content(role, request)},
        ]
        return self.structured.ask(role, messages, reply, check=check, tools=tools)

    # --- internals ---------------------------------------------------------
    def _user_content(self, role: str, request: BaseModel) -> str | list[dict[str, Any]]:
        images: list[tuple[str, bytes]] = []

        def on_bytes(path: tuple[str, ...], data: bytes) -> str:
            images.append((".".join(path), data))
            return f"<image {len(images)}, attached below>"

        payload = redact(request, on_bytes)
        text = f"{load_prompt(role)}\n\n{robot_section(request)}# Request\n```json\n{json.dumps(payload, indent=2)}\n```"
        if not images:
            return text
        parts: list[dict[str, Any]] = [{"type": "text", "text": text}]
        for i, (path, data) in enumerate(images, 1):
            parts.append({"type": "text", "text": f"Image {i} ({path}): {IMAGE_LABELS.get(path, path)}"})
            url = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
            parts.append({"type": "image_url", "image_url": {"url": url}})
        return parts


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
        structured_output=settings.structured_output,
    )
