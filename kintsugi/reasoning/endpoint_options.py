"""The openai backend's own settings (`--set reasoner.options.<key>=value`); light, so listing backends
never imports the SDK."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from kintsugi.core.config import StrictModel


class Learnt(StrictModel):
    """What a campaign's preflight learnt about the endpoint, once, in the campaign's process; every trial's
    settings carry it to the worker processes, so no trial finds it out again."""

    text_mode: dict[Literal["json_schema", "tools"], str] = Field(default_factory=dict)
    """Strict options the server refused or ignored (with its answer): asked for in text from the first call."""
    context_tokens: int | None = None
    """The model's context length, where the preflight could tell."""
    images: str = "sent"
    """"sent" (the endpoint takes them), or what is sent instead and why."""


class OpenAIOptions(StrictModel):
    """What the openai backend sends and what it checks first."""

    images: Literal["send", "measurements"] = "send"
    """send: camera images go to the model (PNG data URLs); measurements: no image is sent, the model works
    from the checks and measurements each request also carries (for text-only models); every call's record
    counts the images withheld."""
    image_max_px: int | None = Field(default=None, ge=32, le=4096)
    """A cap on an image's longer side, below each role's own (`Role.image_max_px`)."""
    max_reply_tokens: int | None = Field(default=None, ge=1)
    """Sent as max_tokens: bounds each reply (unset: the server's default)."""
    preflight: bool = True
    """Ask the endpoint what it can do (images, strict options, context) before a campaign's first trial."""
    context_tokens: int | None = Field(default=None, ge=256)
    """The model's context length, for servers that do not report it (llama.cpp's server and vLLM do)."""
    learnt: Learnt | None = None
    """Set by a campaign's preflight for its trials (not by hand): what it learnt about the endpoint."""
