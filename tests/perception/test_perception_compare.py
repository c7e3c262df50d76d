"""Goal-image comparison used by the insertion check."""

from __future__ import annotations

import numpy as np
import pytest

from kintsugi.perception.compare import compare_to_goal, mask_iou, surface_z_mm
from kintsugi.perception.segment import PerceptionConfig
from kintsugi.perception.synthetic import HoleGeom, PegPose, default_calibration, draw_scene

CALIB = default_calibration()
HOLE = HoleGeom(y=2.0, depth_mm=40.0)
GOAL = draw_scene(CALIB, PegPose(y=2.0, z=-30.0), HOLE, seed=1)  # peg 30 mm deep: top 30 mm above the board


def test_inserted_peg_matches_goal() -> None:
    term = draw_scene(CALIB, PegPose(y=2.6, z=-29.0, tilt_deg=1.0), HOLE, seed=2)
    r = compare_to_goal(term, GOAL, CALIB)
    assert r.passed and r.name == "insert_image"
    assert r.measurements["goal_peg_top_above_surface_mm"] == pytest.approx(30.0, abs=1.0)
    assert abs(r.measurements["top_difference_mm"]) < 3.0
    assert r.measurements["peg_mask_iou"] > 0.8
    assert "matches the goal image" in r.message


def test_peg_resting_on_the_surface_is_too_high() -> None:
    term = draw_scene(CALIB, PegPose(y=2.0, z=-1.0, tilt_deg=3.0), HOLE, seed=3)
    r = compare_to_goal(term, GOAL, CALIB)
    assert not r.passed
    assert r.measurements["top_difference_mm"] == pytest.approx(29.0 + 0.5, abs=2.0)
    assert "does not match the goal image" in r.message


def test_peg_at_goal_height_but_beside_the_hole_fails_on_overlap() -> None:
    term = draw_scene(CALIB, PegPose(y=27.0, z=-30.0), HOLE, seed=4)
    r = compare_to_goal(term, GOAL, CALIB)
    assert not r.passed
    assert abs(r.measurements["top_difference_mm"]) < 1.0
    assert r.measurements["offset_y_mm"] == pytest.approx(25.0, abs=1.0)
    assert r.measurements["peg_mask_iou"] < PerceptionConfig().insert_min_iou


def test_hidden_peg_against_visible_goal_fails_and_both_hidden_pass() -> None:
    hidden = draw_scene(CALIB, PegPose(y=2.0, z=-90.0), HOLE, seed=5)
    r = compare_to_goal(hidden, GOAL, CALIB)
    assert not r.passed and r.measurements["peg_visible"] == 0.0
    assert "peg not visible" in r.message
    both = compare_to_goal(hidden, draw_scene(CALIB, None, HOLE, seed=6), CALIB)
    assert both.passed and both.measurements["peg_mask_iou"] == 1.0


def test_tolerance_is_configurable() -> None:
    term = draw_scene(CALIB, PegPose(y=2.0, z=-25.0), HOLE, seed=7)  # 5 mm higher than goal
    assert not compare_to_goal(term, GOAL, CALIB).passed
    assert compare_to_goal(term, GOAL, CALIB, PerceptionConfig(insert_top_tol_mm=6.0)).passed


def test_surface_falls_back_to_config_without_a_board() -> None:
    dark = np.zeros((240, 320, 3), np.uint8)
    assert surface_z_mm(dark, CALIB, PerceptionConfig(board_surface_z_mm=-4.0)) == -4.0
    assert surface_z_mm(GOAL, CALIB, PerceptionConfig(board_surface_z_mm=-4.0)) == pytest.approx(0.0, abs=0.5)


def test_mask_iou() -> None:
    a = np.zeros((4, 4), np.uint8)
    b = a.copy()
    a[:2] = 255
    b[1:3] = 255
    assert mask_iou(a, b) == pytest.approx(1 / 3)
    assert mask_iou(a * 0, b * 0) == 1.0
