"""An unreachable pose is a failed action: other ways of doing it first, then a recorded failure, never an error.

Unit checks of the alternatives (grasp slid along a lying object, turned about a standing one, a place moved to
a clear spot, the drag back into reach), then whole trials whose workspace is shrunk so the bottle is out of
reach: AgentChord ends as a recorded failure with the reason, no trial error."""

from __future__ import annotations

import numpy as np
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.methods.agentchord.reaching import grasp_alternatives, place_alternatives, pull_vector
from kintsugi.perception.features import ObjectFeatures

BASE = np.array([-0.05, -0.3, 0.12])


def _lying(x: float, y: float, axis=(1.0, 0.0, 0.0)) -> ObjectFeatures:
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    c = np.array([x, y, 0.03])
    return ObjectFeatures(name="bottle", visible=True, n_points=500, fit="primitive", centroid=tuple(c),
                          axis=tuple(a), extent=(0.2, 0.06, 0.06), tilt_deg=90.0, upright=False,
                          extremes={"top": tuple(c + [0, 0, 0.03]), "bottom": tuple(c - [0, 0, 0.03]),
                                    "axis_pos": tuple(c + 0.1 * a), "axis_neg": tuple(c - 0.1 * a)})


def _standing(x: float, y: float) -> ObjectFeatures:
    c = np.array([x, y, 0.1])
    return ObjectFeatures(name="bottle", visible=True, n_points=500, fit="primitive", centroid=tuple(c),
                          axis=(0.0, 0.0, 1.0), extent=(0.2, 0.06, 0.06), tilt_deg=0.0, upright=True,
                          extremes={"top": tuple(c + [0, 0, 0.1]), "bottom": tuple(c - [0, 0, 0.1])})


def test_a_lying_object_is_grasped_off_centre_towards_the_base_first() -> None:
    call = {"action": "grasp", "arm": "right", "obj": "bottle", "pre_grasp_offset": 0.06}
    alts = grasp_alternatives(call, _lying(0.76, -0.19), BASE)
    offsets = [a["grasp_offset"][0] for a in alts]
    assert offsets and offsets[0] < 0.0  # the axis points +x, the base is at -x: slide towards -x first
    assert max(abs(o) for o in offsets) <= 0.04 + 1e-9  # standing it up from farther along swings it wide
    assert all(a["pre_grasp_offset"] == 0.06 and a["obj"] == "bottle" for a in alts)


def test_a_standing_object_is_approached_from_other_sides() -> None:
    call = {"action": "grasp", "arm": "right", "obj": "bottle"}
    alts = grasp_alternatives(call, _standing(0.4, -0.2), BASE)
    ways = [(a.get("yaw_deg"), a.get("pre_grasp_offset")) for a in alts]
    assert len(set(ways)) == len(ways) >= 4 and all(y is None or -180.0 <= y <= 180.0 for y, _ in ways)
    assert any(a.get("pre_grasp_offset", 0.08) < 0.08 for a in alts)  # a shorter approach near the base
    assert grasp_alternatives({**call, "yaw_deg": 10.0}, _standing(0.4, -0.2), BASE) == []  # as asked, no guess


def test_the_drag_goes_towards_the_middle_of_reach() -> None:
    far, near = pull_vector(_lying(0.76, -0.19), BASE), pull_vector(_lying(0.02, -0.43), BASE)
    assert far[0] < -0.1 and np.linalg.norm(far) <= 0.15 + 1e-9  # from the edge of reach back towards the base
    assert float(near @ (np.array([0.02, -0.43]) - BASE[:2])) > 0.0  # from too close, away from the base


def test_a_place_moves_only_as_far_as_its_sub_goal_allows() -> None:
    call = {"action": "place", "arm": "right", "x": 0.4, "y": -0.25}
    cup = _standing(0.4, -0.1).model_copy(update={"name": "cup", "extent": (0.09, 0.09, 0.09)})
    free = place_alternatives(call, [cup], _standing(0.4, -0.25), located=False)
    held = place_alternatives(call, [cup], _standing(0.4, -0.25), located=True)
    dist = lambda a: float(np.hypot(a["x"] - 0.4, a["y"] + 0.25))  # noqa: E731
    assert free and max(map(dist, free)) <= 0.30 + 1e-6 and max(map(dist, held)) <= 0.03 + 1e-6
    for a in free:  # clear of the cup
        assert np.hypot(a["x"] - 0.4, a["y"] + 0.1) >= 0.045 + 0.03 + 0.03 - 1e-6


def test_an_unreachable_object_is_a_recorded_failure_not_an_error() -> None:
    """The workspace ends short of the bottle: nothing can reach it, the trial fails with the reason."""
    r = run_trial(TrialSpec(task="pour-single", method="agentchord", variant="default", condition="none", seed=0,
                            overrides={"motion.workspace_x_m": [0.05, 0.2]}))
    assert r.error is None, r.error
    assert not r.success and not r.framework_success
    assert any(e.kind in ("unreachable", "failed", "replan refused") for e in r.events), \
        [(e.kind, e.detail) for e in r.events]


class _TurnRobot:
    """A right hand holding a bottle beside the body; a turn plans only once the hand is 0.2 m or more out."""

    def __init__(self, tcp: tuple[float, float, float], held: bool = True) -> None:
        self.tcp, self.held, self.bases, self.sim_time = np.array(tcp), held, {"right": BASE}, 1.0

    def arm_state(self, arm: str):  # noqa: ANN201
        from types import SimpleNamespace

        return SimpleNamespace(tcp_pos=tuple(self.tcp), held=frozenset({"bottle"} if self.held else ()))

    def execute(self, call: dict, plan_only: bool = False):  # noqa: ANN201
        from types import SimpleNamespace

        out = call["action"] == "move_by_offset" and any(call["dxyz"]) or self.tcp[0] >= 0.2
        if out and not plan_only and call["action"] == "move_by_offset":
            self.tcp = self.tcp + np.asarray(call["dxyz"], float)
        return SimpleNamespace(planned=bool(out), clipped=False)


def _turner(robot: _TurnRobot):  # noqa: ANN202
    from types import SimpleNamespace

    from kintsugi.core.log import TrialLog
    from kintsugi.methods.agentchord.reaching import Reaching

    r = Reaching.__new__(Reaching)
    r.robot, r.log = robot, TrialLog()
    r._execute = lambda edge, name, args, unplanned_ok=False: robot.execute({"action": name, **args})  # noqa: ARG005
    r.synthesis = SimpleNamespace(adapt=lambda edge, call: {**call, "resynthesized": tuple(robot.tcp)})
    return r


def test_a_turn_out_of_reach_beside_the_body_is_made_after_carrying_the_object_out() -> None:
    from types import SimpleNamespace

    robot = _TurnRobot((0.06, -0.05, 0.18))
    edge = SimpleNamespace(id="re.stand", actions=[SimpleNamespace(name="rotate_eef", args={
        "arm": "right", "angle_deg": 90.0, "axis": "closing"})])
    turn = {"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.0), "drpy_deg": (0.0, 90.0, 0.0)}
    reacher = _turner(robot)
    again = reacher.carry_to_turn(edge, turn)
    assert again is not None and again["action"] == "rotate_eef" and again["resynthesized"][0] >= 0.2
    assert robot.tcp[2] == 0.18 and np.linalg.norm(robot.tcp[:2] - (BASE[:2] + [0.5, 0.0])) < 0.2
    assert [e.kind for e in reacher.log.events] == ["carried to turn"] * 2  # two legs of at most 0.15 m
    assert _turner(_TurnRobot((0.06, -0.05, 0.18), held=False)).carry_to_turn(edge, turn) is None  # nothing held
    assert _turner(_TurnRobot((0.06, -0.05, 0.03))).carry_to_turn(edge, turn) is None  # still on the table
    assert _turner(_TurnRobot((0.06, -0.05, 0.18))).carry_to_turn(edge, {**turn, "dxyz": (0.0, 0.0, 0.05)}) is None
