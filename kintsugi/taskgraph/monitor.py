"""Online failure detection for the active edge (Eq. 12-13), evaluated every control step.

A monitor fires only when its value exceeds the margin epsilon on W consecutive evaluations,
so one noisy frame or a brief contact flicker never triggers a recovery. NaN (inputs not
perceived this step) is not a violation and breaks the streak; tracking loss is the
`visibility` template's job.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from kintsugi.taskgraph.features import Features
from kintsugi.taskgraph.model import Edge, Monitor


@dataclass(frozen=True, slots=True)
class Firing:
    """A monitor fired: which one, its failure mode, the recovery edge to run now (Eq. 13), when."""

    monitor: str
    failure_mode: str
    recovery: str | None
    value: float
    step: int
    """0-based index of the evaluation that completed the window."""


class MonitorBank:
    """The monitors of one edge with their persistence counters; call `step` once per control step.

    `start` is the feature vector when the edge began: monitors with references taken at edge
    start (a `drift` without `ref`) latch them there, or at the first step their object is seen.
    """

    __slots__ = ("monitors", "_eval", "_margin", "_window", "_count", "_checks", "_pending", "values", "steps")

    def __init__(self, monitors: Sequence[Monitor], start: Features | None = None) -> None:
        self.monitors = tuple(monitors)
        self._checks = [m.check if start is None else m.check.bind(start) for m in self.monitors]
        self._eval = [c.evaluate for c in self._checks]
        self._margin = tuple(float(m.margin) for m in self.monitors)
        self._window = tuple(int(m.window) for m in self.monitors)
        self._pending = [i for i, c in enumerate(self._checks) if not c.bound]
        self._count = [0] * len(self.monitors)
        self.values = [float("nan")] * len(self.monitors)
        """The last evaluation of every monitor (for logs and plots)."""
        self.steps = 0

    @classmethod
    def for_edge(cls, edge: Edge, start: Features | None = None) -> "MonitorBank":
        return cls(edge.monitors, start)

    def _bind_pending(self, f: Features) -> None:
        still = []
        for i in self._pending:
            c = self._checks[i].bind(f)
            if c.bound:
                self._checks[i] = c
                self._eval[i] = c.evaluate
            else:
                still.append(i)
        self._pending = still

    def step(self, f: Features) -> Firing | None:
        """Evaluate every monitor once; return the first (declaration order) whose window is complete."""
        if self._pending:
            self._bind_pending(f)
        fired = -1
        count, margin, window, values = self._count, self._margin, self._window, self.values
        for i, ev in enumerate(self._eval):
            v = ev(f)
            values[i] = v
            if v > margin[i]:
                count[i] += 1
                if fired < 0 and count[i] >= window[i]:
                    fired = i
            else:
                count[i] = 0
        step = self.steps
        self.steps = step + 1
        if fired < 0:
            return None
        m = self.monitors[fired]
        return Firing(m.id, m.failure_mode, m.recovery, values[fired], step)

    def reset(self) -> None:
        """Clear every persistence counter (e.g. after the conductor paused execution)."""
        self._count = [0] * len(self.monitors)
