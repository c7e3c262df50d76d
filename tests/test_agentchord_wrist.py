"""Straight-line moves that must not flip the wrist, and the stand-up's choice of hand (pour-dual seeds 0 and 12).

A straight line is a list of IK waypoints each seeded by the previous one. When the seeded solve meets a joint
limit, the solve from home may win on the other wrist branch (q4 + 180, -q5, q6 + 180): the joint-space move
between those two waypoints swings the hand through a half turn. Backing an open hand away must stop short
of that instead (a place's retreat swept its fingers through the bottle it had just stood up)."""

from __future__ import annotations

import numpy as np
import pytest

from kintsugi.methods.agentchord.tops import upright_hand
from kintsugi.tasks.tabletop import actions as A
from kintsugi.tasks.tabletop.config import TabletopConfig
from kintsugi.tasks.tabletop.ik import ArmIK
from kintsugi.tasks.tabletop.motion import Move
from kintsugi.tasks.tabletop.planning import BRANCH_JUMP_DEG, ArmView, Planner

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


def test_backing_away_stops_where_the_wrist_would_flip(planner: Planner) -> None:
    view = _view(planner, AT_LIMIT_DEG)
    steps = planner._back(A.Back(arm="right", retreat_m=0.08), view, {})
    away, home = steps
    assert away.label == "back away" and home.label == "home"
    assert _largest_step_deg(view.q, [away]) <= BRANCH_JUMP_DEG
    # It still backed out some of the way, straight along the approach axis, orientation kept.
    moved = away.tcp[0] - view.pos
    assert 0.01 < float(np.linalg.norm(moved)) < 0.08
    assert float(moved @ -view.rot[:, 2]) == pytest.approx(float(np.linalg.norm(moved)), abs=1e-6)
    assert np.allclose(away.tcp[1], view.rot)


def test_back_without_a_retreat_goes_straight_home(planner: Planner) -> None:
    view = _view(planner, AT_LIMIT_DEG)
    steps = planner._back(A.Back(arm="right"), view, {})
    assert [s.label for s in steps] == ["home"]


def test_a_retreat_the_arm_follows_is_the_whole_line(planner: Planner) -> None:
    home = planner.iks["right"].home
    pos, rot = planner.iks["right"].fk(home)
    view = ArmView(q=home, pos=pos, rot=rot, base=np.array([-0.05, -0.3, 0.0]), touching={})
    away = planner._back(A.Back(arm="right", retreat_m=0.05), view, {})[0]
    assert np.allclose(away.tcp[0], pos - 0.05 * rot[:, 2], atol=1e-9)


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
