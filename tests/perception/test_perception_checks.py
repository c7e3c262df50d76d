"""Table I rules with their exact messages, pose and compression checks."""

from __future__ import annotations

import pytest

from kintsugi.perception import checks
from kintsugi.perception.checks import align_check, compression_check, fit_check, pose_check
from kintsugi.perception.segment import PerceptionConfig, measure
from kintsugi.perception.synthetic import HoleGeom, PegPose, default_calibration, draw_scene, peg_centred_at
from kintsugi.perception.types import Pose

CALIB = default_calibration()
HOLE_Y = 4.0
HOLE = HoleGeom(y=HOLE_Y)


def scene(peg: PegPose | None, hole: HoleGeom | None = HOLE):
    return measure(draw_scene(CALIB, peg, hole, seed=11), CALIB)


@pytest.mark.parametrize(
    ("peg_y", "message", "passed"),
    [
        (HOLE_Y - 10.0, "success", True),  # centre 10 mm left, right edge 10 mm right of H_center
        (HOLE_Y - 30.0, "p_gy was too small.", False),  # right edge 10 mm short of H_center
        (HOLE_Y + 6.0, "p_gy was too big.", False),  # centre already right of H_center
    ],
)
def test_fit_table(peg_y: float, message: str, passed: bool) -> None:
    peg = peg_centred_at(peg_y, z=-3.0, tilt_deg=12.0)  # tilted, corner dipping into the hole
    result = fit_check(scene(peg))
    assert (result.message, result.passed, result.name) == (message, passed, "vision_fit")
    assert result.measurements["peg_center_y_mm"] == pytest.approx(peg_y, abs=1.0)
    assert result.measurements["hole_center_y_mm"] == pytest.approx(HOLE_Y, abs=1.0)


ALIGN_CASES = [
    # (offset of P_center from H_center mm, tilt deg, exact Table I message)
    (0.5, 0.0, "Align success"),
    (-1.5, 10.0, "peg is tilted to the left."),
    (1.5, -10.0, "peg is tilted to the right."),
    (-8.0, 0.0, "p_ey was too small."),
    (8.0, 2.0, "p_ey was too big."),
    (-8.0, 10.0, "peg is tilted to the left. p_gy was too small."),
    (8.0, 10.0, "p_gy was too big. also tilted to the left."),
    (-8.0, -10.0, "p_gy was too small. also tilted to the right."),
    (8.0, -10.0, "p_gy was too big. also tilted to the right."),
]


@pytest.mark.parametrize(("offset", "tilt", "message"), ALIGN_CASES)
@pytest.mark.parametrize("z", [-2.0, -30.0], ids=["on-surface", "in-hole"])
def test_align_table(offset: float, tilt: float, message: str, z: float) -> None:
    peg = peg_centred_at(HOLE_Y + offset, z=z, tilt_deg=tilt)
    result = align_check(scene(peg))
    assert result.message == message
    assert result.passed == (message == "Align success")
    m = result.measurements
    assert m["offset_y_mm"] == pytest.approx(offset, abs=1.0)
    assert m["tilt_deg"] == pytest.approx(tilt, abs=1.0)
    assert (m["align_tol_mm"], m["tilt_tol_deg"]) == (3.0, 5.0)


def test_align_table_covers_every_cell_once() -> None:
    assert len(checks.ALIGN_TABLE) == 9 and len(set(checks.ALIGN_TABLE.values())) == 9
    assert {msg for _, _, msg in ALIGN_CASES} == set(checks.ALIGN_TABLE.values())


def test_align_tolerances_come_from_config() -> None:
    s = scene(peg_centred_at(HOLE_Y + 2.0, z=-2.0, tilt_deg=4.0))
    assert align_check(s).message == "Align success"
    strict = PerceptionConfig(align_tol_mm=1.0, tilt_tol_deg=2.0)
    assert align_check(s, strict).message == "p_gy was too big. also tilted to the left."


@pytest.mark.parametrize(
    ("peg", "hole", "missing"),
    [(None, HOLE, "peg"), (PegPose(y=0, z=5), None, "hole"), (None, None, "peg and hole")],
)
def test_missing_objects_fail_and_say_which(peg, hole, missing: str) -> None:
    s = scene(peg, hole)
    for result in (fit_check(s), align_check(s)):
        assert not result.passed
        assert result.message.startswith(f"{missing} not visible")
        assert result.measurements["peg_visible"] == float(peg is not None)
        assert result.measurements["hole_visible"] == float(hole is not None)


def test_pose_check_uses_only_the_skill_axes() -> None:
    goal, term = Pose(y=10.0, z=-5.0, roll=0.0), Pose(y=10.6, z=20.0, roll=3.0)
    ok = pose_check(goal, term, ["y"])
    assert ok.passed and ok.measurements == {"error_y_mm": pytest.approx(0.6), "error_norm_mm": pytest.approx(0.6), "threshold_mm": 1.0}
    bad = pose_check(goal, term, ["y", "z"])
    assert not bad.passed and bad.measurements["error_z_mm"] == pytest.approx(25.0)
    assert "z off by +25.00 mm" in bad.message


def test_pose_check_norm_and_roll() -> None:
    goal = Pose(y=0.0, z=0.0, roll=0.0)
    assert not pose_check(goal, Pose(y=0.8, z=0.8), ["y", "z"]).passed  # norm 1.13 mm > 1 mm
    assert pose_check(goal, Pose(y=0.6, z=0.6), ["y", "z"]).passed
    assert not pose_check(goal, Pose(y=0.0, z=0.0, roll=2.0), ["y", "z", "roll"]).passed
    assert pose_check(goal, Pose(y=0.0, z=0.0, roll=2.0), ["y", "z", "roll"], threshold_deg=2.5).passed
    assert pose_check(goal, Pose(y=1.5, z=0.0), ["y"], threshold_mm=2.0).passed


def test_compression_check() -> None:
    hit = compression_check(True, 41.234)
    assert not hit.passed and "compression limit reached" in hit.message and "41.2 N" in hit.message
    assert hit.measurements == {"force_z_n": 41.234, "limit_hit": 1.0}
    assert compression_check(False, 3.0).passed
