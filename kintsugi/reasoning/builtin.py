"""The built-in backends' registrations. Each factory imports its module when the backend is built, so
listing the backends (or running offline) never imports the OpenAI SDK."""

from __future__ import annotations

from typing import Any

from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.endpoint_options import OpenAIOptions
from kintsugi.reasoning.scripted import ScriptedOptions


@REASONERS.register("embedded", "deterministic offline reasoner: each role's own rules (OpenCV on the images, "
                    "a symbolic planner, material tables), no model", tags=("offline",))
def _embedded(settings: Any, options: Any) -> Any:
    from kintsugi.reasoning.embedded import make_embedded

    return make_embedded(settings, options)


@REASONERS.register("scripted", "replies from a JSONL file, a trial record's transcript "
                    "(reasoner.options.replies=<file>) or a function (reasoner.options.function=module:callable), "
                    "checked like a model's", tags=("offline", "replay"), config=ScriptedOptions)
def _scripted(settings: Any, options: ScriptedOptions) -> Any:
    from kintsugi.reasoning.scripted import make_scripted

    return make_scripted(settings, options)


@REASONERS.register(
    "openai",
    "any OpenAI-compatible chat-completions endpoint (OpenAI, vLLM, Ollama, llama.cpp): "
    "set reasoner.model, reasoner.base_url, and the key in $OPENAI_API_KEY (or reasoner.api_key_env)",
    tags=("network", "vlm"),
    config=OpenAIOptions,
)
def _openai(settings: Any, options: Any) -> Any:
    from kintsugi.reasoning.openai_backend import make_openai_reasoner

    return make_openai_reasoner(settings, options)
