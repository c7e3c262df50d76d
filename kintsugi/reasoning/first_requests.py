"""The first request each role of a method will send, built from a real first observation of the task.

`first_requests(spec, roles)` runs the trial `spec` up to the roles' first calls: every reasoner the
method builds is wrapped so that a role's first call is captured as it would go out (`Outgoing`: the
system prompt, the request built from what the robot observed, images at the size sent, the strict
options or the text-mode answer format) and then answered offline by the embedded backend, so the
trial goes on to the next role as it would with a working model (a role asking again is answered
offline too). It stops as soon as every role has been captured, the trial ends, or no new role has asked
for `FIRST_S` seconds from the start or `IDLE_S` seconds after the last capture (a role asked only after
a failed attempt may never come). Nothing is sent to the endpoint and nothing is written; the preflight then asks the endpoint to count
the captured requests.
"""

from __future__ import annotations

import signal
import threading
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel

from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning.base import Check, sees_images


FIRST_S = 90.0
"""Wall seconds the dry run waits for the first role's call."""
IDLE_S = 10.0
"""Wall seconds it waits for another role after a capture (the offline answers' own time not counted)."""


class _Enough(BaseException):
    """Ends the dry run (a BaseException: a method's `except Exception` must not swallow it)."""


@dataclass
class _Capture:
    wanted: set[str]
    first: dict[str, Any] = field(default_factory=dict)
    """Role name -> its first `Outgoing`."""
    problem: str | None = None
    """Why the dry run ended before every role was captured (the embedded answer refused, the trial failed)."""
    timed: bool = False

    def arm(self, seconds: float) -> None:
        if self.timed:
            signal.setitimer(signal.ITIMER_REAL, max(seconds, 0.001) if seconds else 0.0)

    def pause(self) -> float:
        """Stop the clock (an offline answer's own time is not counted); the seconds that were left."""
        if not self.timed:
            return 0.0
        left = signal.getitimer(signal.ITIMER_REAL)[0]
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        return left

    def timeout(self, signum: int, frame: Any) -> None:
        self.problem = f"no other role asked within {IDLE_S if self.first else FIRST_S:g} s"
        raise _Enough


_ACTIVE: list[_Capture] = []


class _Capturing:
    """What a method gets for a reasoner during the dry run: captures, then answers offline."""

    def __init__(self, real: Any, capture: _Capture) -> None:
        from kintsugi.reasoning.embedded import EmbeddedReasoner

        self.real, self.capture = real, capture
        self.name = real.name
        self.answerer = EmbeddedReasoner()
        self.last_stats = None

    @property
    def sees_images(self) -> bool:
        return sees_images(self.real)

    def answer(self, role: Any, request: BaseModel, check: Check | None = None) -> BaseModel:
        first = self.capture.first
        left = self.capture.pause()
        new = role.name not in first
        if new:
            first[role.name] = self.real.outgoing(role, request)
            if self.capture.wanted <= first.keys():
                raise _Enough
        try:
            return self.answerer.answer(role, request, check)
        except ReasoningError as exc:
            self.capture.problem = f"the offline answer to {role.name} ended the dry run ({exc})"
            raise _Enough from None
        finally:
            self.capture.arm(IDLE_S if new else left)


def wrap(reasoner: Any) -> Any:
    """`reasoner` itself, or its capturing wrapper while a dry run is active (`make_reasoner` calls this)."""
    if _ACTIVE and callable(getattr(reasoner, "outgoing", None)):
        return _Capturing(reasoner, _ACTIVE[-1])
    return reasoner


def first_requests(spec: Any, roles: list[str]) -> tuple[dict[str, Any], str | None]:
    """({role name: Outgoing} for the roles the trial reached, why it stopped early or None)."""
    from kintsugi.core.runner import run_trial

    capture = _Capture(set(roles))
    capture.timed = (threading.current_thread() is threading.main_thread() and hasattr(signal, "setitimer")
                     and signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, None))
    previous = signal.signal(signal.SIGALRM, capture.timeout) if capture.timed else None
    _ACTIVE.append(capture)
    try:
        capture.arm(FIRST_S)
        record = run_trial(spec.model_copy(update={"video": None}))
        if record.error and capture.problem is None:
            capture.problem = f"the dry-run trial ended: {record.error.splitlines()[0]}"
    except _Enough:
        pass
    finally:
        capture.arm(0)
        if capture.timed:
            signal.signal(signal.SIGALRM, previous)
        _ACTIVE.remove(capture)
    return capture.first, capture.problem


__all__ = ["first_requests", "wrap"]
