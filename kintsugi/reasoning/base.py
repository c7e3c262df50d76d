"""The reasoner protocol and the transcript wrapper that records every call.

A backend answers any registered role (`kintsugi.reasoning.roles`) through `Reasoner.answer`;
methods ask through `roles.ask`. Wrapping a backend in `RecordingReasoner` gives the trial a
transcript (role, request, reply, latency, tokens, attempts, error) so a user can read why the
robot moved.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Literal, Protocol, TypeVar, runtime_checkable

from pydantic import BaseModel, Field

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ReasoningError

if TYPE_CHECKING:
    from kintsugi.reasoning.roles import Role

Check = Callable[[Any], Any]
"""A reply -> the reply to use (possibly corrected); raises ReasoningError (e.g. BadReply) to reject it."""


@dataclass(frozen=True)
class CallStats:
    """Cost of a backend's most recent call; backends set `last_stats` to one of these.

    `attempts` counts model round trips of the repair loop (1 = first reply was
    valid, 2 = one repair); HTTP-level retries done by an SDK are not counted.
    `output_mode` is how the reply's format was enforced ("strict" by the server,
    "text" by the prompt and a tolerant parser); `output_note` says why it switched.
    """

    tokens_in: int = 0
    tokens_out: int = 0
    attempts: int = 1
    output_mode: str | None = None
    output_note: str | None = None
    images_sent: int = 0
    images_withheld: int = 0


class CallRecord(StrictModel):
    """One reasoner call as kept in the trial transcript."""

    role: str = Field(min_length=1, max_length=40, description="the role's registered name (judge, composer, ...)")
    backend: str
    request: dict
    reply: dict | None
    error: str | None = None
    latency_s: float = 0.0
    tokens_in: int = 0
    tokens_out: int = 0
    attempts: int = 1
    output_mode: Literal["strict", "text"] | None = None
    """How an endpoint enforced the reply format (None for backends without one, e.g. embedded)."""
    output_note: str | None = None
    """Set on the call where the backend fell back from strict to text output, with the reason."""
    images_sent: int = 0
    images_withheld: int = 0
    """Camera images left out of this call's request (`reasoner.options.images=measurements`): the model
    worked from the checks and measurements alone."""


@runtime_checkable
class Reasoner(Protocol):
    """A backend: answers any role's request with a reply of the role's reply type.

    `check` (the role's and the caller's checks, combined) must run on every reply before it is
    returned; a backend that can ask again (a model endpoint) sends its complaint back for one
    repair. Implementations raise `ReasoningError` (or a subclass) when they cannot give a valid
    reply; they may expose `last_stats: CallStats | None` for accounting, and `sees_images = False`
    when they never look at camera images (methods then leave them out of requests; see `sees_images`).
    """

    name: str

    def answer(self, role: "Role", request: BaseModel, check: Check | None = None) -> BaseModel: ...


def sees_images(reasoner: Any) -> bool:
    """Whether requests to this backend should carry camera images: a model looks at them, rules that
    measure other observations (or replayed replies) do not. Backends say so with `sees_images`; True
    when they do not say."""
    return bool(getattr(reasoner, "sees_images", True))


def describe_bytes(data: bytes) -> str:
    """Short stand-in for binary data in transcripts and prompts."""
    kind = "png" if data[:8] == b"\x89PNG\r\n\x1a\n" else "binary"
    return f"<{kind} {len(data)} bytes>"


def redact(value: Any, on_bytes: Callable[[tuple[str, ...], bytes], Any] | None = None,
           _path: tuple[str, ...] = ()) -> Any:
    """JSON-safe copy of `value` with bytes replaced (by `on_bytes(path, data)` or a size note).

    Non-finite floats become strings so the transcript stays valid JSON.
    """
    if isinstance(value, BaseModel):
        value = value.model_dump(mode="python")
    if isinstance(value, (bytes, bytearray)):
        return on_bytes(_path, bytes(value)) if on_bytes else describe_bytes(bytes(value))
    if isinstance(value, dict):
        return {str(k): redact(v, on_bytes, _path + (str(k),)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [redact(v, on_bytes, _path + (str(i),)) for i, v in enumerate(value)]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


R = TypeVar("R", bound=BaseModel)


class RecordingReasoner:
    """Wraps a backend; appends one `CallRecord` per call to `records`.

    A `ReasoningError` from the backend is recorded with its message and re-raised, so failed
    calls appear in the transcript too. Pass an existing list as `records` to share one
    transcript between several wrappers.
    """

    def __init__(self, inner: Reasoner, records: list[CallRecord] | None = None) -> None:
        self.inner = inner
        self.name = inner.name
        self.records: list[CallRecord] = records if records is not None else []

    @property
    def last_stats(self) -> CallStats | None:
        return getattr(self.inner, "last_stats", None)

    @property
    def sees_images(self) -> bool:
        return sees_images(self.inner)

    def answer(self, role: "Role", request: BaseModel, check: Check | None = None) -> BaseModel:
        return self.record(role.name, lambda req: self.inner.answer(role, req, check), request)

    @property
    def total_latency_s(self) -> float:
        return sum(r.latency_s for r in self.records)

    @property
    def errors(self) -> int:
        return sum(1 for r in self.records if r.error is not None)

    def record(self, role: str, method: Callable[[Any], R], request: BaseModel) -> R:
        """Call `method(request)` and append its record under `role`."""
        if hasattr(self.inner, "last_stats"):
            self.inner.last_stats = None  # type: ignore[attr-defined]  # never report a stale call
        start = time.perf_counter()
        reply: R | None = None
        error: str | None = None
        try:
            reply = method(request)
            return reply
        except ReasoningError as exc:
            error = f"{type(exc).__name__}: {exc}"
            raise
        finally:
            latency = time.perf_counter() - start
            if reply is not None or error is not None:
                stats = getattr(self.inner, "last_stats", None) or CallStats()
                self.records.append(
                    CallRecord(
                        role=role,
                        backend=self.name,
                        request=redact(request),
                        reply=redact(reply) if reply is not None else None,
                        error=error,
                        latency_s=latency,
                        tokens_in=stats.tokens_in,
                        tokens_out=stats.tokens_out,
                        attempts=stats.attempts,
                        output_mode=stats.output_mode,
                        output_note=stats.output_note,
                        images_sent=stats.images_sent,
                        images_withheld=stats.images_withheld,
                    )
                )
