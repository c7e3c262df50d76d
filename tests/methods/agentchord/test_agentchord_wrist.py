"""Straight-line moves that must not flip the wrist, and the stand-up's choice of hand (pour-dual seeds 0 and 12).

A straight line is a list of IK waypoints each seeded by the previous one. When the seeded solve meets a joint
limit, the solve from home may win on the other wrist branch (q4 + 180, -q5, q6 + 180): the joint-space move
between those two waypoints swings the hand through a half turn. Backing an open hand away must stop short
of that instead (a place's retreat swept its fingers through the bottle it had just stood up)."""

from __future__ import annotations

import numpy as np
import pytest

from kintsugi.methods.agentchord.tops import upright_hand
from kintsugi.worlds.tabletop import actions as A
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.ik import ArmIK
from kintsugi.worlds.tabletop.motion import Move
from kintsugi.worlds.tabletop.planning import BRANCH_JUMP_DEG, ArmView, Planner

# pour-dual seed 12: the right hand has just released the bottle it stood up, its last roll near its limit.
AT_LIMIT_DEG = [-0.9, 35.1, 133.6, -34.7, -80.7, -173.6]


@pytest.fixture(scope="module")
def planner() -> Planner:
    cfg = TabletopConfig()
    return Planner(cfg, {a: ArmIK(cfg.robot, cfg.motion, a) for a in ("left", "right")}, {})


def _view(planner: Planner, q_deg: list[float]) -> ArmView:
    q = np.radians(q_deg)
    pos, rot = planner.iks["right"].fk(q)
    return ArmView(q=q, pos=pos, rot=rot, base=np.array([-0.05, -0.3, 0.0]), touching={})


def _largest_step_deg(start: np.ndarray, moves: list) -> float:
    path = [start, *[q for m in moves if isinstance(m, Move) for q in m.waypoints]]
    return float(np.degrees(np.abs(np.diff(np.array(path), axis=0))).max())


def test_the_full_retreat_line_would_flip_the_wrist(planner: Planner) -> None:
    """The premise: followed to its end, this 8 cm retreat leaves the wrist's branch."""
    view = _view(planner, AT_LIMIT_DEG)
    goal = view.pos - 0.08 * view.rot[:, 2]
    move = planner._linear("right", (view.pos, view.rot), (goal, view.rot), view.q, "retreat", "retreat")
    assert _largest_step_deg(view.q, [move]) > 90.0


def test_a_retreat_stops_where_the_wrist_would_flip(planner: Planner) -> None:
    view = _view(planner, AT_LIMIT_DEG)
    goal = view.pos - 0.08 * view.rot[:, 2]
    away = planner._linear_prefix("right", (view.pos, view.rot), (goal, view.rot), view.q, "retreat")
    assert away is not None and _largest_step_deg(view.q, [away]) <= BRANCH_JUMP_DEG
    # It still backed out some of the way, straight along the approach axis, orientation kept.
    moved = away.tcp[0] - view.pos
    assert 0.01 < float(np.linalg.norm(moved)) < 0.08
    assert float(moved @ -view.rot[:, 2]) == pytest.approx(float(np.linalg.norm(moved)), abs=1e-6)
    assert np.allclose(away.tcp[1], view.rot)


def test_back_can_first_raise_the_hand_straight_up(planner: Planner) -> None:
    view = _view(planner, AT_LIMIT_DEG)
    rise, home = planner._back(A.Back(arm="right", rise_m=0.08), view, {})
    assert rise.label == "rise" and home.label == "home"
    assert _largest_step_deg(view.q, [rise]) <= BRANCH_JUMP_DEG
    assert np.allclose(rise.tcp[0], view.pos + [0.0, 0.0, 0.08], atol=1e-9) and np.allclose(rise.tcp[1], view.rot)


def test_back_without_a_rise_goes_straight_home(planner: Planner) -> None:
    view = _view(planner, AT_LIMIT_DEG)
    steps = planner._back(A.Back(arm="right"), view, {})
    assert [s.label for s in steps] == ["home"]


def test_a_line_the_arm_follows_is_kept_whole(planner: Planner) -> None:
    home = planner.iks["right"].home
    pos, rot = planner.iks["right"].fk(home)
    goal = pos - 0.05 * rot[:, 2]
    away = planner._linear_prefix("right", (pos, rot), (goal, rot), home, "retreat")
    assert np.allclose(away.tcp[0], goal, atol=1e-9)


def test_upright_hand_puts_the_top_up_and_faces_away_from_the_shoulder() -> None:
    shoulder = np.array([-0.05, -0.3, 0.12])
    tcp = np.array([0.45, -0.3, 0.18])
    for top_in_hand in ([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]):
        hand = upright_hand(top_in_hand, tcp, shoulder)
        assert np.allclose(hand @ np.array(top_in_hand), [0.0, 0.0, 1.0], atol=1e-9)
        assert np.allclose(hand[:, 2], [1.0, 0.0, 0.0], atol=1e-9)  # approach: away from the shoulder
    # The two ways round of a top-down grasp end a half turn apart about the approach axis.
    a, b = upright_hand([1.0, 0.0, 0.0], tcp, shoulder), upright_hand([-1.0, 0.0, 0.0], tcp, shoulder)
    assert np.allclose(a[:, 0], -b[:, 0], atol=1e-9) and np.allclose(a[:, 2], b[:, 2], atol=1e-9)
    assert upright_hand([0.0, 0.0, 1.0], tcp, shoulder) is None  # a top along the approach: no such turn


def test_a_side_grasp_beside_a_held_cup_is_taken_from_the_facing_that_clears_it() -> None:
    """pour-dual seed 1: the bottle fell upright against the cup the left hand holds up. Taken the default way
    (facing away from the arm's base), one open finger passes inside the cup's footprint, just under its
    bottom, and the lift carries the cup up; the synthesised grasp comes in from the other side."""
    from types import SimpleNamespace

    from kintsugi.methods.agentchord.keyframes import TabletopKeyframes
    from kintsugi.methods.agentchord.synthesis import FINGER_CLEAR_M, EdgeSynthesis
    from kintsugi.worlds.tabletop.clearance import gap
    from kintsugi.methods.agentchord.tops import Heads, Tops
    from kintsugi.worlds.tabletop.planning import side_rotation

    def upright(name, x, y, r, z0, z1):  # noqa: ANN001, ANN202
        return SimpleNamespace(name=name, visible=True, centroid=(x, y, (z0 + z1) / 2), axis=(0.0, 0.0, 1.0),
                               upright=True, tilt_deg=0.0, extent=(z1 - z0, 2 * r, 2 * r),
                               extremes={"top": (x, y, z1), "bottom": (x, y, z0), "axis_pos": (x, y, z1),
                                         "axis_neg": (x, y, z0)})

    seen = {"bottle": upright("bottle", 0.513, -0.111, 0.03, 0.0, 0.2),
            "cup": upright("cup", 0.506, -0.035, 0.045, 0.118, 0.208)}
    cfg = TabletopConfig()
    kf = TabletopKeyframes(cfg)
    home = np.degrees(kf.iks["right"].home)

    class Robot:
        bases = {"right": np.array([-0.05, -0.3, 0.0]), "left": np.array([-0.05, 0.3, 0.0])}

        def features(self, names=None):  # noqa: ANN001, ANN202
            return {k: v for k, v in seen.items() if names is None or k in names}

        def arm_state(self, arm):  # noqa: ANN001, ANN202
            return SimpleNamespace(joints_deg=tuple(home))

    syn = EdgeSynthesis(None, Robot(), kf, Tops(), Heads())  # type: ignore[arg-type]
    call = {"action": "grasp", "arm": "right", "obj": "bottle", "pre_grasp_offset": 0.08}
    out = syn._clear_grasp_call(dict(call))
    assert out.get("yaw_deg") is not None
    c = np.array(seen["bottle"].centroid)
    closing = side_rotation(np.radians(out["yaw_deg"]))[:, 1]
    fingers = [c + w * closing for w in (-0.05, 0.05)]
    assert min(gap(p, 0.085, 0.235, seen["cup"]) for p in fingers) >= FINGER_CLEAR_M
    # With the cup moved away, the grasp is left as the composer gave it.
    seen["cup"] = upright("cup", 0.506, 0.2, 0.045, 0.118, 0.208)
    assert syn._clear_grasp_call(dict(call)) == call
