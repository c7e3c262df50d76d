"""What a method reports while it runs: skills, events, recovery transitions, transcript."""

from __future__ import annotations

import time
from typing import Any

from pydantic import BaseModel

from kintsugi.core.record import Event, SkillLog


class TrialLog:
    """What a method reports while it runs: skills, events, recovery transitions, transcript.

    `echo` (optional) tells the story live on a console; `status` feeds video overlays.
    """

    def __init__(self, echo=None, on_status=None, started: float | None = None) -> None:  # noqa: ANN001
        """`started` is the trial's start on `time.perf_counter`'s clock (default: now): skills and events
        carry their wall time since then, so a user sees where a trial's time went."""
        self._t0 = time.perf_counter() if started is None else started
        self.skills: list[SkillLog] = []
        self.events: list[Event] = []
        self.transitions: list[tuple[str, str]] = []
        self.transcript: list[dict[str, Any]] = []
        self.executions: dict[str, int] = {}
        self.method_figures: BaseModel | None = None
        self._echo = echo
        self._on_status = on_status

    def skill(self, entry: SkillLog) -> None:
        if entry.wall_s is None:
            entry = entry.model_copy(update={"wall_s": self._wall()})
        self.skills.append(entry)
        self.executions[entry.skill] = self.executions.get(entry.skill, 0) + 1

    def event(self, t: float, kind: str, detail: str = "") -> None:
        self.events.append(Event(t=round(t, 4), kind=kind, detail=detail, wall_s=self._wall()))
        if self._echo is not None:
            from rich.markup import escape

            self.say(f"[dim]{t:6.2f}s[/dim] {escape(kind)}: {escape(detail)}", markup=True)

    def _wall(self) -> float:
        return round(time.perf_counter() - self._t0, 3)

    def figures(self, figures: BaseModel) -> None:
        """The method's own typed figures for the record (`method_figures`); a later call replaces them."""
        self.method_figures = figures

    def transition(self, failed: str, first_recovery: str) -> None:
        self.transitions.append((failed, first_recovery))

    def say(self, text: str, markup: bool = False) -> None:
        """Tell one line of the story. The text is shown verbatim (a model reply may hold `[/INST]`);
        with `markup=True` it is Rich markup, and the caller must `rich.markup.escape` dynamic parts."""
        if self._echo is not None:
            if not markup:
                from rich.markup import escape  # lazy: workers without an echo never import rich

                text = escape(text)
            self._echo(text)

    def status(self, label: str, verdict: str | None = None) -> None:
        if self._on_status is not None:
            self._on_status(label, verdict)
