"""Property: on random drawn scenes, tilt is measured and Table I verdicts follow the drawn geometry."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from kintsugi.perception.checks import ALIGN_TABLE, align_check, align_class, fit_check
from kintsugi.perception.segment import PerceptionConfig, measure
from kintsugi.perception.synthetic import HoleGeom, PegPose, default_calibration, draw_scene, visible_box_mm

CALIB = default_calibration()
CFG = PerceptionConfig()
MARGIN_MM = 1.0  # stay this far from any decision boundary
MARGIN_DEG = 1.5


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    peg_y=st.floats(-30.0, 30.0),
    peg_z=st.floats(-45.0, 15.0),
    tilt=st.floats(-20.0, 20.0),
    hole_y=st.floats(-15.0, 15.0),
    seed=st.integers(0, 1000),
)
def test_random_scenes_match_geometry(peg_y: float, peg_z: float, tilt: float, hole_y: float, seed: int) -> None:
    peg = PegPose(y=peg_y, z=peg_z, tilt_deg=tilt)
    # A corner just above/below the board line leaves a sub-pixel sliver whose visibility is a coin toss.
    assume(all(abs(z) > 2.0 for _, z in peg.corners()))
    box = visible_box_mm(peg)
    assume(box is not None and box[3] - box[2] >= 8.0)
    left, right, _, _ = box
    p_center, p_edge = (left + right) / 2, right

    m = measure(draw_scene(CALIB, peg, HoleGeom(y=hole_y), seed=seed), CALIB, CFG)
    assert m.peg is not None and m.hole is not None
    assert m.peg.tilt_deg == pytest.approx(tilt, abs=1.5)
    assert m.peg.center_mm[0] == pytest.approx(p_center, abs=1.0)

    if abs(p_center - hole_y) > MARGIN_MM and abs(p_edge - hole_y) > MARGIN_MM:
        if p_center <= hole_y < p_edge:
            expected_fit = "success"
        elif p_center <= hole_y:
            expected_fit = "p_gy was too small."
        else:
            expected_fit = "p_gy was too big."
        event(f"fit: {expected_fit}")
        assert fit_check(m).message == expected_fit

    offset = p_center - hole_y
    if abs(abs(offset) - CFG.align_tol_mm) > MARGIN_MM and abs(abs(tilt) - CFG.tilt_tol_deg) > MARGIN_DEG:
        expected = align_class(offset, tilt, CFG)
        measured = align_class(m.peg.center_mm[0] - m.hole.center_mm[0], m.peg.tilt_deg, CFG)
        assert measured == expected
        event(f"align: {expected}")
        assert align_check(m, CFG).message == ALIGN_TABLE[expected]
