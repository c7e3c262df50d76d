"""A place back where the held object was first seen goes where it was last taken up, once it was taken up
again elsewhere, and only with room around that spot.

Golden behaviour of the edge synthesis on a scripted robot (perceived objects and pad touch), and the trials that
showed each half: pour-single seed 67 at drop p 0.10 (the carry back to where the bottle was first seen cost 35
control steps more than code-as-monitor, which re-planned from where the bottle lay), and seed 70 (set down
where it fell, beside the cup, the hand knocked the cup over)."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from kintsugi.methods.agentchord.method import metrics_of
from kintsugi.methods.agentchord.synthesis import EdgeSynthesis
from kintsugi.methods.agentchord.tops import Heads, Tops
from kintsugi.taskgraph.model import TaskGraph
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

FIRST = (0.38, -0.25)
"""Where the bottle was first seen (the compiled place goes there)."""


@dataclass
class _Feat:
    centroid: tuple[float, float, float] | None
    extent: tuple[float, float, float] | None


@dataclass
class _Arm:
    touching: dict[str, int]

    @property
    def held(self) -> frozenset[str]:
        return frozenset(k for k, n in self.touching.items() if n == 2)


@dataclass
class _Sense:
    touching: frozenset[str]


@dataclass
class _Robot:
    """The bottle in the right hand at `bottle`; the cup at `cup`."""

    bottle: tuple[float, float]
    cup: tuple[float, float] = (0.47, -0.02)
    holds: bool = True
    seen: list[str] = field(default_factory=list)

    def features(self, names=None):  # noqa: ANN001, ANN201 - the robot's perception interface
        out = {"bottle": _Feat((*self.bottle, 0.1), (0.06, 0.06, 0.2)),
               "cup": _Feat((*self.cup, 0.045), (0.09, 0.09, 0.09))}
        return {k: v for k, v in out.items() if names is None or k in names}

    def arm_state(self, arm: str) -> _Arm:
        return _Arm({"bottle": 2} if self.holds and arm == "right" else {})

    def grip_sense(self, arm: str) -> _Sense:
        return _Sense(frozenset({"bottle"}) if self.holds and arm == "right" else frozenset())


def _synthesis(robot: _Robot) -> EdgeSynthesis:
    place = {"name": "place", "args": {"arm": "right", "x": FIRST[0], "y": FIRST[1]}}
    g = TaskGraph.model_validate({"task": "t", "start": "a", "goal": "b", "nodes": [{"id": "a"}, {"id": "b"}],
                                  "edges": [{"id": "e", "source": "a", "target": "b", "actions": [place]}]})
    return EdgeSynthesis(g, robot, keyframes=None, tops=Tops(), heads=Heads(), seen={"bottle": FIRST})


def _place(s: EdgeSynthesis, x: float = FIRST[0], y: float = FIRST[1]) -> tuple[float, float]:
    call = s.adapt(s.graph.edge("e"), {"action": "place", "arm": "right", "x": x, "y": y})
    return call["x"], call["y"]


def test_a_place_goes_where_the_object_was_taken_up_again_when_that_spot_is_clear() -> None:
    robot = _Robot(bottle=(0.45, -0.16))
    s = _synthesis(robot)
    s.grasp_outcome({"arm": "right", "obj": "bottle"})
    assert _place(s) == (0.45, -0.16)
    assert _place(s, 0.5, 0.2) == (0.5, 0.2)  # a place elsewhere (a region) is the caller's, kept


def test_a_place_stays_where_first_seen_when_the_object_was_taken_up_there_or_the_new_spot_is_crowded() -> None:
    robot = _Robot(bottle=(FIRST[0] + 0.01, FIRST[1]))  # the nominal pick: a centimetre off is the same spot
    s = _synthesis(robot)
    s.grasp_outcome({"arm": "right", "obj": "bottle"})
    assert _place(s) == FIRST
    robot = _Robot(bottle=(0.47, -0.10))  # fell beside the cup: 8 cm apart, 0.5 cm of room
    s = _synthesis(robot)
    s.grasp_outcome({"arm": "right", "obj": "bottle"})
    assert _place(s) == FIRST
    robot = _Robot(bottle=(0.45, -0.16))
    s = _synthesis(robot)
    robot.holds = False  # a grasp that closed on nothing takes nothing up
    s.grasp_outcome({"arm": "right", "obj": "bottle"})
    robot.holds = True
    assert _place(s) == FIRST


def _trial(seed: int):  # noqa: ANN202
    r = run_trial(TrialSpec(task="pour-single", method="agentchord", variant="default", condition="drop", seed=seed,
                            overrides={"disturbance.drop_p": 0.1}))
    assert r.error is None, r.error
    assert r.success and r.framework_success
    return r


@pytest.mark.slow
def test_pour_single_seed_67_sets_the_bottle_down_where_it_took_it_up_again() -> None:
    assert metrics_of(_trial(67)).episode_steps <= 1630  # code-as-monitor's; 1665 from the first-seen spot


@pytest.mark.slow
def test_pour_single_seed_70_keeps_the_bottle_away_from_the_cup() -> None:
    _trial(70)


def _stand_up(robot: _Robot) -> EdgeSynthesis:
    """A stand-up edge (grasp lying, lift, turn about the closing axis, place) whose place was filled from where
    the bottle lay when the graph was planned (a re-plan after it rolled)."""
    actions = [{"name": "grasp", "args": {"arm": "right", "obj": "bottle"}},
               {"name": "move_by_offset", "args": {"arm": "right", "dxyz": [0.0, 0.0, 0.15]}},
               {"name": "rotate_eef", "args": {"arm": "right", "angle_deg": 90.0, "axis": "closing"}},
               {"name": "place", "args": {"arm": "right", "x": 0.11, "y": 0.03}}]
    g = TaskGraph.model_validate({
        "task": "t", "start": "a", "goal": "b",
        "nodes": [{"id": "a"}, {"id": "b", "constraints": [{"kind": "upright", "object": "bottle", "tol_deg": 15}]}],
        "edges": [{"id": "e", "source": "a", "target": "b", "actions": actions}]})
    return EdgeSynthesis(g, robot, keyframes=None, tops=Tops(), heads=Heads(), seen={"bottle": FIRST})


def test_a_stand_up_sets_the_object_down_where_it_was_first_seen_when_that_spot_is_clear() -> None:
    robot = _Robot(bottle=(0.11, 0.03))  # rolled up to the robot's body, where it was taken up again
    s = _stand_up(robot)
    s.grasp_outcome({"arm": "right", "obj": "bottle"})
    assert _place(s, 0.11, 0.03) == FIRST
    assert _place(s) == FIRST  # compiled to the first spot: kept there, not moved to where it was taken up


def test_a_stand_up_keeps_its_place_when_the_first_spot_is_taken() -> None:
    robot = _Robot(bottle=(0.11, 0.03), cup=(FIRST[0] + 0.05, FIRST[1]))  # the cup stands there now
    s = _stand_up(robot)
    s.grasp_outcome({"arm": "right", "obj": "bottle"})
    assert _place(s, 0.11, 0.03) == (0.11, 0.03)
