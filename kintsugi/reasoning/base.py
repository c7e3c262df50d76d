"""The reasoner protocol and the transcript wrapper that records every call.

A method talks to any backend through `Reasoner`; wrapping it in
`RecordingReasoner` gives the trial a transcript (role, request, reply,
latency, tokens, attempts, error) so a user can read why the robot moved.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Callable, Protocol, TypeVar, runtime_checkable

from pydantic import BaseModel

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    CallRecord,
    JudgeReply,
    JudgeRequest,
    PlanReply,
    PlanRequest,
    Role,
)


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


@runtime_checkable
class Reasoner(Protocol):
    """One object answering the three roles of the recovery loop.

    Implementations raise `ReasoningError` (or a subclass) when they cannot give a
    valid reply; they may expose `last_stats: CallStats | None` for accounting.
    """

    name: str

    def judge(self, request: JudgeRequest) -> JudgeReply: ...

    def analyze(self, request: AnalyzeRequest) -> AnalyzeReply: ...

    def plan(self, request: PlanRequest) -> PlanReply: ...


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
    """Wraps a reasoner; appends one `CallRecord` per call to `records`.

    A `ReasoningError` from the inner reasoner is recorded with its message and
    re-raised, so failed calls appear in the transcript too. Pass an existing
    list as `records` to share one transcript between several wrappers.
    """

    def __init__(self, inner: Reasoner, records: list[CallRecord] | None = None) -> None:
        self.inner = inner
        self.name = inner.name
        self.records: list[CallRecord] = records if records is not None else []

    @property
    def last_stats(self) -> CallStats | None:
        return getattr(self.inner, "last_stats", None)

    def judge(self, request: JudgeRequest) -> JudgeReply:
        return self._call("judge", self.inner.judge, request)

    def analyze(self, request: AnalyzeRequest) -> AnalyzeReply:
        return self._call("analyze", self.inner.analyze, request)

    def plan(self, request: PlanRequest) -> PlanReply:
        return self._call("plan", self.inner.plan, request)

    @property
    def total_latency_s(self) -> float:
        return sum(r.latency_s for r in self.records)

    @property
    def errors(self) -> int:
        return sum(1 for r in self.records if r.error is not None)

    def _call(self, role: Role, method: Callable[[Any], R], request: BaseModel) -> R:
        return self.record(role, method, request)

    def record(self, role: str, method: Callable[[Any], R], request: BaseModel) -> R:
        """Call `method(request)` and append its record under `role` (any role, see reasoning/roles.py)."""
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
                    )
                )
