"""A grasp clears its own way in: the joint-space move to the pose above the object must not sweep the open hand
through another perceived object (after a drop the empty hand is often right beside the cup the other hand holds
up). When it would, the hand first rises straight up over the objects, and goes home as well when even that is not
enough. Only perceived geometry is read."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from kintsugi.perception.features import ObjectFeatures
from kintsugi.worlds.tabletop import actions as A
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.ik import ArmIK
from kintsugi.worlds.tabletop.motion import Move
from kintsugi.worlds.tabletop.planning import SWEEP_CLEAR_M, ArmView, Planner, side_rotation

BASE = np.array([-0.05, -0.3, 0.0])


@pytest.fixture(scope="module")
def planner() -> Planner:
    cfg = TabletopConfig()
    side = SimpleNamespace(grasp="side_if_upright")
    return Planner(cfg, {a: ArmIK(cfg.robot, cfg.motion, a) for a in ("left", "right")},
                   {"bottle": side, "cup": side, "post": side})


def _cylinder(name: str, x: float, y: float, z0: float, height: float, radius: float) -> ObjectFeatures:
    top, bottom = (x, y, z0 + height), (x, y, z0)
    return ObjectFeatures(name=name, visible=True, n_points=500, fit="primitive", centroid=(x, y, z0 + height / 2),
                          axis=(0.0, 0.0, 1.0), extent=(height, 2 * radius, 2 * radius), tilt_deg=0.0, upright=True,
                          extremes={"top": top, "bottom": bottom, "axis_pos": top, "axis_neg": bottom})


def _hand_at(planner: Planner, xyz: tuple[float, float, float]) -> ArmView:
    pos = np.array(xyz)
    rot = side_rotation(float(np.arctan2(pos[1] - BASE[1], pos[0] - BASE[0])))
    ik = planner.iks["right"]
    r = ik.solve(pos, rot, ik.home)
    assert r.ok
    return ArmView(q=r.q, pos=pos, rot=rot, base=BASE, touching={})


def _labels(steps: list) -> list[str]:
    return [s.label for s in steps]


BOTTLE = _cylinder("bottle", 0.35, -0.35, 0.0, 0.2, 0.03)
HELD_CUP = _cylinder("cup", 0.45, -0.10, 0.12, 0.10, 0.04)  # held up by the other hand, beside the right one


def test_from_home_with_nothing_in_the_way_the_grasp_goes_straight_in(planner: Planner) -> None:
    home = planner.iks["right"].home
    pos, rot = planner.iks["right"].fk(home)
    view = ArmView(q=home.copy(), pos=pos, rot=rot, base=BASE, touching={})
    steps = planner._grasp(A.Grasp(arm="right", obj="bottle"), view, {"bottle": BOTTLE})
    assert _labels(steps) == ["open", "above bottle side-on (upright)", "pre-grasp bottle", "approach bottle", "close"]


def test_a_hand_beside_the_held_cup_rises_over_it_first(planner: Planner) -> None:
    view = _hand_at(planner, (0.45, -0.20, 0.12))
    feats = {"bottle": BOTTLE, "cup": HELD_CUP}
    hover = next(s for s in planner._grasp(A.Grasp(arm="right", obj="bottle"), view, {"bottle": BOTTLE})
                 if s.label.startswith("above"))
    assert planner._sweep_gap("right", view.q, hover.waypoints[-1], [HELD_CUP, BOTTLE]) < SWEEP_CLEAR_M  # premise
    steps = planner._grasp(A.Grasp(arm="right", obj="bottle"), view, feats)
    assert _labels(steps)[:3] == ["open", "rise clear", "above bottle side-on (upright)"]
    rise = steps[1]
    assert isinstance(rise, Move)
    assert np.allclose(rise.tcp[0][:2], view.pos[:2], atol=1e-9) and rise.tcp[0][2] > 0.22  # straight up, over the cup
    assert np.allclose(rise.tcp[1], view.rot)
    assert planner._sweep_gap("right", rise.waypoints[-1], steps[2].waypoints[-1], [HELD_CUP, BOTTLE]) >= SWEEP_CLEAR_M


def test_when_rising_is_not_enough_the_hand_goes_home_first(planner: Planner) -> None:
    view = _hand_at(planner, (0.45, -0.20, 0.12))
    post = _cylinder("post", 0.40, -0.28, 0.0, 0.8, 0.04)  # taller than any rise, between the hand and the bottle
    steps = planner._grasp(A.Grasp(arm="right", obj="bottle"), view, {"bottle": BOTTLE, "post": post})
    assert _labels(steps)[:4] == ["open", "rise clear", "home", "above bottle side-on (upright)"]


def test_an_object_the_cameras_lost_is_no_obstacle(planner: Planner) -> None:
    view = _hand_at(planner, (0.45, -0.20, 0.12))
    lost = ObjectFeatures(name="cup", visible=False, n_points=0, fit="raw", note="occluded")
    plain = planner._grasp(A.Grasp(arm="right", obj="bottle"), view, {"bottle": BOTTLE})
    steps = planner._grasp(A.Grasp(arm="right", obj="bottle"), view, {"bottle": BOTTLE, "cup": lost})
    assert _labels(steps) == _labels(plain)


def _lying(name: str, x: float, y: float, radius: float = 0.03, half: float = 0.1) -> ObjectFeatures:
    c = (x, y, radius)
    return ObjectFeatures(name=name, visible=True, n_points=500, fit="primitive", centroid=c, axis=(1.0, 0.0, 0.0),
                          extent=(2 * half, 2 * radius, 2 * radius), tilt_deg=90.0, upright=False,
                          extremes={"top": (x, y, 2 * radius), "bottom": (x, y, 0.0), "axis_pos": (x + half, y, radius),
                                    "axis_neg": (x - half, y, radius)})


def test_at_the_edge_of_reach_the_grasp_skips_the_pose_above_and_comes_to_the_pre_grasp_pose(planner: Planner) -> None:
    """A fallen bottle out at the edge of reach (pour-dual seed 25: 0.63 m out): pointing down, the hand reaches
    the pre-grasp pose 6 cm over it but not the pose above its top; the grasp comes in from there."""
    home = planner.iks["right"].home
    pos, rot = planner.iks["right"].fk(home)
    view = ArmView(q=home.copy(), pos=pos, rot=rot, base=BASE, touching={})
    near = planner._grasp(A.Grasp(arm="right", obj="bottle", pre_grasp_offset=0.06), view,
                          {"bottle": _lying("bottle", 0.45, -0.2)})
    assert _labels(near)[1:] == ["above bottle top-down (fallen)", "pre-grasp bottle", "approach bottle", "close"]
    far = _lying("bottle", 0.627, -0.007)
    steps = planner._grasp(A.Grasp(arm="right", obj="bottle", pre_grasp_offset=0.06), view, {"bottle": far})
    assert "pre-grasp bottle" not in _labels(steps) and _labels(steps)[-2:] == ["approach bottle", "close"]
    first = next(s for s in steps if isinstance(s, Move))
    assert first.tcp[0][2] == pytest.approx(far.centroid[2] + 0.06, abs=1e-6)  # the pre-grasp pose, not higher


def _propped(elevation_deg: float, x: float = 0.45, y: float = -0.15) -> ObjectFeatures:
    """A bottle lying along y with its far end raised `elevation_deg` (leaning on something)."""
    e = np.radians(elevation_deg)
    axis = (0.0, float(np.cos(e)), float(np.sin(e)))
    c = np.array([x, y, 0.03 + 0.1 * np.sin(e)])
    ends = [tuple(c + s * 0.1 * np.array(axis)) for s in (1, -1)]
    return ObjectFeatures(name="bottle", visible=True, n_points=500, fit="primitive", centroid=tuple(c), axis=axis,
                          extent=(0.2, 0.06, 0.06), tilt_deg=90.0 - elevation_deg, upright=False,
                          extremes={"top": (x, y, c[2] + 0.03), "bottom": (x, y, 0.0), "axis_pos": ends[0],
                                    "axis_neg": ends[1]})


def _grasp_rot(planner: Planner, f: ObjectFeatures) -> np.ndarray:
    home = planner.iks["right"].home
    pos, rot = planner.iks["right"].fk(home)
    view = ArmView(q=home.copy(), pos=pos, rot=rot, base=BASE, touching={})
    steps = planner._grasp(A.Grasp(arm="right", obj="bottle", pre_grasp_offset=0.06), view, {"bottle": f})
    return next(s for s in steps if isinstance(s, Move) and s.label == "approach bottle").tcp[1]


@pytest.mark.parametrize("elevation", [15.0, 30.0, 40.0])
def test_a_bottle_propped_up_is_taken_square_to_its_axis(planner: Planner, elevation: float) -> None:
    """Leaning 30 degrees on the cup (pour-single seed 86), a hand straight down met the raised end with its palm
    and closed on nothing ten times; pitched about its closing axis, it approaches square to the bottle."""
    f = _propped(elevation)
    rot = _grasp_rot(planner, f)
    closing, approach = rot[:, 1], rot[:, 2]
    assert abs(closing @ np.array(f.axis)) < 1e-6 and abs(closing[2]) < 1e-6  # still across it, level
    assert abs(approach @ np.array(f.axis)) < 1e-6  # square to the axis
    assert approach[2] == pytest.approx(-np.cos(np.radians(elevation)), abs=1e-6)  # coming down, pitched by it


@pytest.mark.parametrize("elevation", [0.0, 5.0])
def test_a_bottle_lying_on_the_table_is_still_taken_straight_down(planner: Planner, elevation: float) -> None:
    rot = _grasp_rot(planner, _propped(elevation))
    assert rot[:, 2] == pytest.approx([0.0, 0.0, -1.0], abs=1e-9)


def test_a_side_on_hand_right_over_the_block_it_lost_rises_until_it_can_turn_down(planner: Planner) -> None:
    """Handover seed 25: the placing hand (side-on, 13 cm up) lost the block, which fell just below it. The hand
    is already over the block's top, but turning to point down from there sweeps the fingers through it; it
    rises in steps until the turn passes, instead of going home to turn (0.36 s longer). The hand and the
    perceived block are those of that trial."""
    p = Planner(planner.cfg, planner.iks, {**planner.shapes, "block": SimpleNamespace(grasp="top")})
    top, bottom = (0.3997, -0.2496, 0.05), (0.3997, -0.2496, 0.0)
    block = ObjectFeatures(name="block", visible=True, n_points=500, fit="primitive", centroid=(0.3997, -0.2496, 0.025),
                           axis=(0.0, 0.0, 1.0), extent=(0.0487, 0.0613, 0.0596), tilt_deg=None, upright=None,
                           extremes={"top": top, "bottom": bottom, "axis_pos": top, "axis_neg": bottom})
    pos = np.array([0.4007, -0.2596, 0.1297])
    rot = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    view = ArmView(q=np.array([-0.2281, 0.7266, 1.8173, 1.3811, 1.6986, -2.5558]), pos=pos, rot=rot, base=BASE,
                   touching={})
    steps = p._grasp(A.Grasp(arm="right", obj="block"), view, {"block": block})
    hover = next(s for s in steps if s.label.startswith("above"))
    assert p._sweep_gap("right", view.q, hover.waypoints[-1], [block]) < SWEEP_CLEAR_M  # premise: no straight turn
    assert _labels(steps)[:3] == ["open", "rise clear", "above block top-down"]
    rise = steps[1]
    assert np.allclose(rise.tcp[0][:2], pos[:2], atol=1e-9) and pos[2] < rise.tcp[0][2] <= pos[2] + 0.25
    assert p._sweep_gap("right", rise.waypoints[-1], hover.waypoints[-1], [block]) >= SWEEP_CLEAR_M
