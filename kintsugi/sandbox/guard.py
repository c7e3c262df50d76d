"""The bound on cost code inside the control loop.

The probe measures a program once, on sample inputs. Code whose work depends on the state (an `if`
on where the tool is) can pass it in microseconds and take seconds per call on the states the loop
meets. Every call the loop makes therefore runs under a `LoopBound`: a call that uses far more CPU
time than its probe measured (`factor` x, and more than `floor_s`, so a loaded machine's jitter
never trips it), more than the loop's own budget (`budget_s`), or more than `wall_s` on the clock
raises a SandboxError of kind `overrun`. On the main thread interval timers (CPU and wall) interrupt
the call itself (the language has no loops, so the interpreter reaches the next statement within
one whole-array operation); elsewhere the call is measured and refused as soon as it returns.
"""

from __future__ import annotations

import signal
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

from kintsugi.core.errors import SandboxError


@dataclass(frozen=True)
class LoopBound:
    factor: float = 50.0
    """A call using this many times the CPU time its probe measured..."""
    floor_s: float = 0.05
    """...and more than this is a runaway (a loaded machine's jitter stays far below)."""
    budget_s: float = 0.5
    """No call may use more CPU time than this, whatever its probe measured (the loop replans at 10 Hz)."""
    wall_s: float = 0.75
    """Nor take longer than this on the clock: a runaway is stopped within a second however loaded the machine."""

    def limit(self, probed_s: float | None) -> float:
        """CPU seconds one call of a function the probe measured at `probed_s` per call may use."""
        if probed_s is None or probed_s <= 0:
            return self.budget_s
        return min(self.budget_s, max(self.floor_s, self.factor * probed_s))


class _Overrun(BaseException):
    """Raised by a timer inside a call; a BaseException, so the program's own error handling never catches it."""


def _raise(signum: int, frame: Any) -> None:
    raise _Overrun


TIMERS = ((signal.ITIMER_PROF, signal.SIGPROF), (signal.ITIMER_REAL, signal.SIGALRM))


def bounded(name: str, limit_s: float, probed_s: float | None, run: Callable[[], Any],
            wall_s: float = LoopBound.wall_s) -> Any:
    """`run()` (one call of cost function `name`) within `limit_s` CPU seconds and `wall_s` seconds, or a
    SandboxError('overrun'). The timers are used only on the main thread and when no one else armed them."""
    t0, c0 = time.perf_counter(), time.thread_time()
    timer = (threading.current_thread() is threading.main_thread()
             and all(signal.getitimer(which)[0] == 0 for which, _ in TIMERS))
    previous: list[Any] = []
    stopped = False
    if timer:
        previous = [signal.signal(sig, _raise) for _, sig in TIMERS]
        signal.setitimer(signal.ITIMER_PROF, limit_s)
        signal.setitimer(signal.ITIMER_REAL, wall_s)
    try:
        try:
            out = run()
        finally:
            if timer:
                for which, _ in TIMERS:
                    signal.setitimer(which, 0)
    except _Overrun:
        out, stopped = None, True
    finally:
        for (_, sig), old in zip(TIMERS, previous):
            signal.signal(sig, old if old is not None else signal.SIG_DFL)
    cpu, wall = time.thread_time() - c0, time.perf_counter() - t0
    if stopped or cpu > limit_s or wall > wall_s:
        probed = f" (its probe measured {probed_s * 1000:.2f} ms)" if probed_s else ""
        verb = "was stopped after" if stopped else "took"
        raise SandboxError("overrun", f"{name}() {verb} {wall:.2f} s ({cpu:.2f} s of CPU) in the control loop{probed}; "
                                      f"the loop allows {limit_s:.3g} s of CPU per call: its work depends on the state")
    return out
