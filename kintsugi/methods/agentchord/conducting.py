"""What the conductor is configured with and counts, and what an edge's monitors read.

`ConductorConfig` (budgets, branch or backtrack), `Metrics` (episode steps, recoveries, recovery latency),
`ConductorError`; and the reads of a monitor's checks: whether a check is proprioceptive (sampled every
control step), which arm a firing concerns, which objects an edge or a node's guards watch.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import KintsugiError
from kintsugi.taskgraph.model import Edge, TaskGraph
from kintsugi.taskgraph.monitor import Firing


class ConductorError(KintsugiError):
    """The conductor cannot go on (action budget spent, a recovery node with no way back)."""


class Interrupted(Exception):
    """A step observer (a monitor, a recovery's loss watch) stopped an action. Raised so that an action's way
    round (a drag, a push, a carry, a set-down) does not go on issuing moves the same watch stops at their first
    step: the edge that runs the action reads the watch and decides what follows."""


class ConductorConfig(StrictModel):
    max_actions: int = 200
    """Atomic actions per episode before the conductor gives up (a recovery loop never ends a trial hanging)."""
    max_recoveries: int = 10
    """Recoveries (or backtracks) per episode before the conductor gives up."""
    max_replans: int = 2
    """Re-plans from the current observation per trial (the paper's fallback; each costs the planning calls
    again), whatever asked for them: a recovery that keeps failing its merge check or keeps being disturbed, an
    action no arm reaches, a goal check that fails at the end of the graph. With none left the trial ends as a
    recorded failure ("gave up ... no re-plan left")."""
    on_failure: Literal["branch", "backtrack"] = "branch"
    """branch: the pre-compiled forward recovery (AgentChord); backtrack: back to the latest nominal node whose
    sub-goal still holds and re-run the nominal edges from there (AC-BT, ReKep-style)."""


@dataclass
class Metrics:
    episode_steps: int = 0
    """Control steps spent in atomic actions (the paper's episode steps)."""
    actions: int = 0
    recoveries: int = 0
    recovery_latency_steps: list[int] = field(default_factory=list)
    """Per recovery: control steps from the monitor's firing to the recovery's first command."""
    firings: list[str] = field(default_factory=list)
    keyframe_solves: int = 0
    replans: int = 0
    """Fallback re-plans so far (any reason; `ConductorConfig.max_replans` bounds them), recorded in the run's
    figures."""
    fired_at: int | None = None
    """Control step of the latest firing whose recovery has not issued its first command yet."""


def proprioceptive(check: Any) -> bool:
    """A check that reads only the arms' own sensors (no perceived object geometry): per-control-step."""
    return all(role == "arm" or feature is None for _, role, feature in check.refs())


def moves_an_arm(edge: Edge) -> bool:
    """The edge moves an arm (anything but opening a hand, which the settle before it has just done while the
    objects came to rest)."""
    return any(a.name != "open_gripper" for a in edge.actions)


def guard_objects(graph: TaskGraph, node: str) -> set[str]:
    """The objects the guards of the edges out of `node` read."""
    return {e for x in graph.out_edges(node) for c in x.guard for e, role, _ in c.refs() if role != "arm"}


def firing_arm(edge: Edge, firing: Firing) -> str | None:
    """The arm the fired monitor watches (the first arm any of the edge's monitors reads when it names none)."""
    mine = [m for m in edge.monitors if m.id == firing.monitor] or list(edge.monitors)
    return next((e for m in mine for e, role, _ in m.check.refs() if role == "arm"), None)


def objects_of(edge: Edge) -> set[str]:
    """The objects the edge's monitors read."""
    names: set[str] = set()
    for m in edge.monitors:
        for entity, role, _ in m.check.refs():
            if role != "arm":
                names.add(entity)
    return names


VERDICT_UPRIGHT_DEG = 8.0
"""The goal check's `upright` tolerance at most: stricter than the tabletop scorers' 10 degrees by perception's
error on a standing object's axis, so the method never calls a leaning object upright when a judge would not."""


def strict(constraints: Any) -> list:
    """The goal's constraints as the verdict reads them: `upright` no looser than VERDICT_UPRIGHT_DEG."""
    return [c.model_copy(update={"tol_deg": min(c.tol_deg, VERDICT_UPRIGHT_DEG)}) if c.kind == "upright" else c
            for c in constraints]
