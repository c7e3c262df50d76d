"""A trial = task x method x variant x condition x seed -> one TrialRecord.

`run_trial` never raises for a failure inside the trial: an exception or a
diverging simulation becomes the record's `error`, so a campaign goes on.
"""

from __future__ import annotations

import time
import traceback
from typing import Any, Literal

from pydantic import Field

from kintsugi.config import StrictModel


class ReasonerSettings(StrictModel):
    """Which reasoner backend a method uses, and how to reach it."""

    backend: str = "embedded"
    model: str | None = None
    base_url: str | None = None
    api_key_env: str = "OPENAI_API_KEY"
    timeout_s: float = 60.0
    max_retries: int = 3
    structured_output: Literal["auto", "strict", "text"] = "auto"
    """strict: server-enforced JSON schema / tool calls; text: JSON asked for in the prompt; auto: strict until
    the server refuses or ignores it, then text."""


class TrialSpec(StrictModel):
    task: str
    method: str
    variant: str
    condition: str
    seed: int
    overrides: dict[str, Any] = Field(default_factory=dict)
    reasoner: ReasonerSettings = ReasonerSettings()
    video: str | None = None

    @property
    def key(self) -> str:
        """Identity of a trial inside a campaign (resume skips keys already recorded)."""
        return f"{self.task}/{self.method}/{self.variant}/{self.condition}/{self.seed}"


class SkillLog(StrictModel):
    """One execution of one skill, as the robot saw it (plus the method's verdict)."""

    skill: str
    goal: dict[str, float]
    terminal: dict[str, float]
    reached: bool
    timed_out: bool = False
    compression_limit: bool = False
    recovery: bool = False
    verdict: bool | None = None
    message: str = ""
    sim_time: float = 0.0


class Event(StrictModel):
    t: float
    kind: str
    detail: str = ""


class TrialRecord(StrictModel):
    key: str
    task: str
    method: str
    variant: str
    condition: str
    seed: int
    params: dict[str, Any] = Field(default_factory=dict)
    success: bool = False
    framework_success: bool = False
    executions: dict[str, int] = Field(default_factory=dict)
    extra_executions: dict[str, int] = Field(default_factory=dict)
    transitions: list[tuple[str, str]] = Field(default_factory=list)
    skills: list[SkillLog] = Field(default_factory=list)
    events: list[Event] = Field(default_factory=list)
    sim_time: float = 0.0
    wall_time: float = 0.0
    physics_steps: int = 0
    reasoning_calls: int = 0
    reasoning_latency_s: float = 0.0
    reasoning_errors: int = 0
    transcript: list[dict[str, Any]] = Field(default_factory=list)
    error: str | None = None
    video: str | None = None
    details: dict[str, Any] = Field(default_factory=dict)
    """Task-specific figures (the task's own typed model, dumped), e.g. a pour's max tilt over the cup."""

    def without_timings(self) -> dict[str, Any]:
        """The record minus wall-clock fields: equal for equal seeds."""
        data = self.model_dump(mode="json", exclude={"wall_time", "reasoning_latency_s"})
        for call in data["transcript"]:
            call.pop("latency_s", None)
        return data


def run_trial(spec: TrialSpec) -> TrialRecord:
    """Run one trial; any exception becomes a recorded failed trial, never a lost one."""
    from kintsugi.tasks import TASKS, load_all

    start = time.perf_counter()
    try:
        load_all()
        task = TASKS.get(spec.task).factory()
        record = task.run(spec)
    except Exception as exc:  # noqa: BLE001 - a campaign must survive any trial failure
        record = TrialRecord(
            key=spec.key,
            task=spec.task,
            method=spec.method,
            variant=spec.variant,
            condition=spec.condition,
            seed=spec.seed,
            error=f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=4)}",
        )
    return record.model_copy(update={"wall_time": time.perf_counter() - start})


class TrialLog:
    """What a method reports while it runs: skills, events, recovery transitions, transcript.

    `echo` (optional) tells the story live on a console; `status` feeds video overlays.
    """

    def __init__(self, echo=None, on_status=None) -> None:  # noqa: ANN001 - plain callables
        self.skills: list[SkillLog] = []
        self.events: list[Event] = []
        self.transitions: list[tuple[str, str]] = []
        self.transcript: list[dict[str, Any]] = []
        self.executions: dict[str, int] = {}
        self._echo = echo
        self._on_status = on_status

    def skill(self, entry: SkillLog) -> None:
        self.skills.append(entry)
        self.executions[entry.skill] = self.executions.get(entry.skill, 0) + 1

    def event(self, t: float, kind: str, detail: str = "") -> None:
        self.events.append(Event(t=round(t, 4), kind=kind, detail=detail))
        if self._echo is not None:
            from rich.markup import escape

            self.say(f"[dim]{t:6.2f}s[/dim] {escape(kind)}: {escape(detail)}", markup=True)

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
