"""A CoRAL-family trial's own figures (`method_figures`): where its priors and cost came from, and
each attempt's beliefs, cost code, verdict, system identification and adaptation."""

from __future__ import annotations

from typing import Any

from kintsugi.core.config import StrictModel
from kintsugi.core.record import Figures


class CoralAttempt(StrictModel):
    """One attempt of a CoRAL-family trial: what it planned with, how it went, how it was adapted."""

    attempt: int
    beliefs_before: dict[str, dict[str, float]]
    """Mass and friction per object the planning world held for this attempt."""
    source: str
    """The cost code the attempt ran."""
    stages: list[dict[str, Any]]
    regions: list[dict[str, Any]]
    knobs: dict[str, Any]
    reached: bool = False
    """The attempt's own verdict: its last stage's done condition held and no constraint of the path broke."""
    cost_error: str | None = None
    broken: str | None = None
    """Why a constraint the instruction sets over the whole path failed the attempt (a thing it forbids touching
    came too close), if one did."""
    code_ms_per_step: float | None = None
    """Wall-clock cost of the cost code per control step (varies between equal trials)."""
    mppi_ms_per_step: float | None = None
    """Wall-clock MPPI iteration time per control step (varies between equal trials)."""
    history: dict[str, Any] | None = None
    """What the adaptation was shown of this attempt (`AttemptHistory`)."""
    sysid: dict[str, Any] | None = None
    """The system identification fit after it (`SysIdSummary`), when one ran."""
    adaptation: str | None = None
    """The adaptation's diagnosis, or why there was none."""
    adaptation_notes: list[str] | None = None
    beliefs_after: dict[str, dict[str, float]] | None = None
    code_changed: bool | None = None


class CoralFigures(Figures):
    """A CoRAL-family trial's own figures (`method_figures`): where its priors and cost came from, and
    per attempt the beliefs it planned with, the cost code, the stages, the adaptation and the timings."""

    variant: str
    priors: dict[str, dict[str, Any]] = {}
    plan_from: str | None = None
    """`formulation`, or `memory episode <id>` when a remembered plan replaced the formulation."""
    memory: dict[str, Any] | None = None
    """How many episodes the memory held and the best one's similarity score."""
    memory_beliefs: dict[str, dict[str, float]] | None = None
    """The beliefs carried over from the remembered episode."""
    attempts: list[CoralAttempt] = []
    time_breakdown_wall_s: dict[str, float] = {}
    """Wall seconds of the trial by where they went: planning (MPPI iterations), physics (the robot acting: the
    simulation, its sensors, the inner-rate checks), sysid, reasoning (the roles' replies with their checks and
    probes), other (varies between equal trials)."""
