"""Perception on real MuJoCo renders of the peg world (320x240 PNGs saved from PegWorld.render()).

Truth recorded when the frames were rendered: the hole's y (trial parameter)
and the peg body's tilt from its orientation matrix. They pin the HSV
thresholds and the tilt sign convention to what the simulator actually draws.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from kintsugi.perception import align_check, compare_to_goal, fit_check, measure
from kintsugi.perception.types import CameraCalibration

DATA = Path(__file__).resolve().parents[1] / "data"
# PegWorld.calibration() for the default PegTaskConfig camera.
CALIB = CameraCalibration(width=320, height=240, px_per_mm=1.6, cu=160.0, cv=120.0, y0_mm=-10.0, z0_mm=30.0)


def load(name: str) -> np.ndarray:
    return cv2.cvtColor(cv2.imread(str(DATA / f"peg_render_{name}.png")), cv2.COLOR_BGR2RGB)


@pytest.mark.parametrize(
    ("name", "hole_y", "tilt", "fit_msg", "align_msg"),
    [
        ("round_0_fit", 0.0, 5.41, "success", "peg is tilted to the left. p_gy was too small."),
        ("square_12_fit", 12.0, 16.93, "success", "peg is tilted to the left."),
        ("round_0_insert", 0.0, 0.43, "p_gy was too big.", "Align success"),
        ("round_5_align", 5.0, -4.85, "success", "p_ey was too small."),
    ],
)
def test_real_render(name: str, hole_y: float, tilt: float, fit_msg: str, align_msg: str) -> None:
    m = measure(load(name), CALIB)
    assert m.peg is not None and m.hole is not None
    assert m.peg.tilt_deg == pytest.approx(tilt, abs=0.5)
    assert m.hole.center_mm[0] == pytest.approx(hole_y, abs=0.5)
    assert m.hole.top_mm == pytest.approx(0.0, abs=0.7)  # board surface is z = 0
    assert m.hole.right_mm - m.hole.left_mm == pytest.approx(42.0, abs=1.3)  # 40 mm peg + 2 mm clearance
    assert fit_check(m).message == fit_msg
    assert align_check(m).message == align_msg


def test_real_render_goal_comparison() -> None:
    goal = load("round_0_insert")
    same = compare_to_goal(goal, goal, CALIB)
    assert same.passed and same.measurements["peg_top_above_surface_mm"] == pytest.approx(80.6, abs=1.0)
    before = compare_to_goal(load("round_0_fit"), goal, CALIB)
    assert not before.passed and before.measurements["top_difference_mm"] > 10.0
