"""What a trial is (`TrialSpec`) and what it leaves (`TrialRecord`), with the typed figure sections."""

from __future__ import annotations

import json
from typing import Any, ClassVar, Literal, Self

from pydantic import Field, ValidationError, model_validator

from kintsugi.core.config import StrictModel


class ReasonerSettings(StrictModel):
    """Which reasoner backend a method uses, and how to reach it.

    The fields every backend may read are here; `options` holds the backend's own settings,
    validated by the settings class it registered with (`--set reasoner.options.<key>=value`,
    e.g. the scripted backend's `replies` file)."""

    backend: str = "embedded"
    model: str | None = None
    base_url: str | None = None
    api_key_env: str = "OPENAI_API_KEY"
    timeout_s: float = 60.0
    max_retries: int = 3
    structured_output: Literal["auto", "strict", "text"] = "auto"
    """strict: server-enforced JSON schema / tool calls; text: JSON asked for in the prompt; auto: strict until
    the server refuses or ignores it, then text."""
    options: dict[str, Any] = Field(default_factory=dict)
    """The backend's own settings (checked by its settings class when the reasoner is built)."""


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

    def identity(self) -> dict[str, Any]:
        """The fields a record copies from its spec (and a campaign checks it did)."""
        return {"key": self.key, "task": self.task, "method": self.method, "variant": self.variant,
                "condition": self.condition, "seed": self.seed}


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
    """The absolute sim time (s) at which the skill ended, on the trial's one clock, in every system;
    a skill's duration is the difference to the previous skill's (or the start's) time."""
    wall_s: float | None = None
    """Wall-clock seconds since the trial started, when the skill ended (None in older records)."""


class Event(StrictModel):
    t: float
    """Sim time (s) on the trial's one clock."""
    kind: str
    detail: str = ""
    wall_s: float | None = None
    """Wall-clock seconds since the trial started, when the event was logged (None in older records)."""


class Figures(StrictModel):
    """A typed part of a record: a task's scored figures (`task_figures`) or a method's own
    (`method_figures`). Tables read them back with `of(record)`; no figure travels in events."""

    slot: ClassVar[str] = "method_figures"

    @classmethod
    def of(cls, record: "TrialRecord") -> Self | None:
        """This record's figures as `cls`, or None when the record holds none of this kind."""
        data = getattr(record, cls.slot)
        if not data:
            return None
        try:
            return cls.model_validate(data)
        except ValidationError:
            return None


class TaskFigures(Figures):
    """A task's ground-truth figures (what its scorer measured), e.g. a pour's tilt over the cup."""

    slot: ClassVar[str] = "task_figures"


class TrialRecord(StrictModel):
    """One trial. The fields every trial has are top-level; a task's and a method's own figures are
    typed sections (`task_figures`, `method_figures`), written through the runner and read by tables
    through their `Figures` class."""

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
    transitions: list[tuple[str, str]] = Field(default_factory=list)
    """(failed step, first step of its recovery), for every recovery the method started."""
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
    task_figures: dict[str, Any] = Field(default_factory=dict)
    """The task's `TaskFigures`, dumped (its scorer's measurements)."""
    method_figures: dict[str, Any] = Field(default_factory=dict)
    """The method's `Figures`, dumped (e.g. AgentChord's episode steps, CoRAL's attempts)."""

    @model_validator(mode="before")
    @classmethod
    def _older_layout(cls, data: Any) -> Any:
        """Records written before figures had their own sections still load: `details` holds the
        task's figures (and the method's under `method`), peg records carry `extra_executions`,
        AgentChord's figures travel in a `metrics` event."""
        if not isinstance(data, dict) or not ({"details", "extra_executions"} & set(data)):
            return data
        data = dict(data)
        details = dict(data.pop("details", None) or {})
        method = dict(details.pop("method", None) or {})
        extra = data.pop("extra_executions", None)
        if extra:
            method["extra_executions"] = extra
        events = list(data.get("events") or [])
        for event in [e for e in events if isinstance(e, dict) and e.get("kind") == "metrics"]:
            try:
                method |= json.loads(event.get("detail") or "{}")
            except json.JSONDecodeError:
                continue
            events.remove(event)
        data["events"] = events
        data.setdefault("task_figures", details)
        data.setdefault("method_figures", method)
        return data

    def without_timings(self) -> dict[str, Any]:
        """The record minus wall-clock fields (and figures named `*_ms_per_step`, `*_wall_s`): equal for
        equal seeds."""
        data = self.model_dump(mode="json", exclude={"wall_time", "reasoning_latency_s"})
        for call in data["transcript"]:
            call.pop("latency_s", None)
        for entry in data["events"] + data["skills"]:
            entry.pop("wall_s", None)
        for slot in ("task_figures", "method_figures"):
            data[slot] = _without_wall_clock(data[slot])
        return data


WALL_CLOCK_SUFFIXES = ("_ms_per_step", "_wall_s")
"""Figures whose names end so are measured on the wall clock: they differ between equal trials."""


def _without_wall_clock(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _without_wall_clock(v) for k, v in value.items() if not k.endswith(WALL_CLOCK_SUFFIXES)}
    if isinstance(value, list):
        return [_without_wall_clock(v) for v in value]
    return value
