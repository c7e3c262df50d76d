"""Segmentation and measurement on drawn scenes with known geometry."""

from __future__ import annotations

import numpy as np
import pytest

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.perception.segment import HsvRange, PerceptionConfig, board_surface_v, measure, peg_mask
from kintsugi.perception.synthetic import HoleGeom, PegPose, default_calibration, draw_scene, visible_box_mm
from kintsugi.perception.tilt import estimate_tilt, fold90, rect_tilt

CALIB = default_calibration()
HOLE = HoleGeom(y=0.0)


@pytest.mark.parametrize("tilt", [-20.0, -15.0, -10.0, -7.5, -5.0, -2.5, 0.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0])
@pytest.mark.parametrize("z", [10.0, -20.0, -45.0])  # in the air, partly inserted, mostly inserted (stub)
def test_tilt_sign_and_magnitude(tilt: float, z: float) -> None:
    peg = PegPose(y=4.0, z=z, tilt_deg=tilt)
    m = measure(draw_scene(CALIB, peg, HOLE, seed=int(tilt * 10 + z) % 1000), CALIB)
    assert m.peg is not None
    assert m.peg.tilt_deg == pytest.approx(tilt, abs=1.0)


def test_stub_wider_than_tall_reads_small_tilt_not_ninety() -> None:
    # Only ~8 mm of a 40 mm wide peg shows: minAreaRect's long side is the top edge.
    peg = PegPose(y=0.0, z=-52.0, tilt_deg=6.0)
    left, right, bottom, top = visible_box_mm(peg)
    assert right - left > 3 * (top - bottom)
    m = measure(draw_scene(CALIB, peg, HOLE), CALIB)
    assert m.peg.tilt_method == "hull_edges"
    assert m.peg.tilt_deg == pytest.approx(6.0, abs=1.0)


@pytest.mark.parametrize("tilt", [-70.0, -40.0, 30.0, 60.0, 85.0])
def test_large_tilts_of_a_fully_visible_peg_keep_the_full_range(tilt: float) -> None:
    calib = default_calibration(px_per_mm=1.0)
    m = measure(draw_scene(calib, PegPose(y=0.0, z=45.0, tilt_deg=tilt, length_mm=80.0), None), calib)
    assert m.peg.tilt_method == "min_area_rect"
    assert m.peg.tilt_deg == pytest.approx(tilt, abs=1.0)


def test_rect_tilt_ignores_opencv_angle_convention() -> None:
    # Axis-aligned tall and wide boxes: 0 and 90 whatever minAreaRect's angle range is.
    tall = np.array([[[10, 10]], [[20, 10]], [[20, 60]], [[10, 60]]], np.int32)
    wide = np.array([[[10, 10]], [[60, 10]], [[60, 20]], [[10, 20]]], np.int32)
    assert rect_tilt(tall)[0] == pytest.approx(0.0, abs=1e-6)
    assert rect_tilt(wide)[0] == pytest.approx(90.0, abs=1e-6)
    # Top leaning left: top at smaller u than bottom -> positive.
    lean_left = np.array([[[20, 12]], [[30, 10]], [[40, 60]], [[30, 62]]], np.int32)
    assert estimate_tilt(lean_left, (100, 100))[0] == pytest.approx(11.31, abs=0.5)
    mirrored = (lean_left * np.array([-1, 1]) + np.array([100, 0])).astype(np.int32)
    assert estimate_tilt(mirrored, (200, 100))[0] == pytest.approx(-11.31, abs=0.5)
    assert fold90(-45.0) == 45.0 and fold90(100.0) == pytest.approx(10.0)


@pytest.mark.parametrize(("y", "z", "tilt"), [(0.0, 10.0, 0.0), (12.3, -10.0, 8.0), (-17.0, -35.0, -12.0), (30.0, 5.0, 15.0)])
def test_centres_and_edges_within_one_mm(y: float, z: float, tilt: float) -> None:
    peg = PegPose(y=y, z=z, tilt_deg=tilt)
    hole = HoleGeom(y=-6.4, depth_mm=25.0)
    m = measure(draw_scene(CALIB, peg, hole, seed=3), CALIB)
    left, right, bottom, top = visible_box_mm(peg)
    assert m.peg.center_mm[0] == pytest.approx((left + right) / 2, abs=1.0)
    assert m.peg.center_mm[1] == pytest.approx((bottom + top) / 2, abs=1.0)
    assert m.peg.edge_mm[0] == pytest.approx(right, abs=1.0)
    assert m.peg.top_mm == pytest.approx(top, abs=1.0)
    assert m.peg.bottom_mm == pytest.approx(max(bottom, 0.0), abs=1.0)
    assert m.hole.center_mm[0] == pytest.approx(-6.4, abs=1.0)
    assert m.hole.center_mm[1] == pytest.approx(-12.5, abs=1.0)
    assert m.hole.right_mm - m.hole.left_mm == pytest.approx(42.0, abs=1.0)


def test_missing_peg_and_hole_give_none_not_errors() -> None:
    only_hole = measure(draw_scene(CALIB, None, HOLE), CALIB)
    assert only_hole.peg is None and only_hole.hole is not None
    only_peg = measure(draw_scene(CALIB, PegPose(y=0, z=5), None), CALIB)
    assert only_peg.peg is not None and only_peg.hole is None
    black = measure(np.zeros((240, 320, 3), np.uint8), CALIB)
    assert black.peg is None and black.hole is None
    hidden = measure(draw_scene(CALIB, PegPose(y=0, z=-80), HOLE), CALIB)
    assert hidden.peg is None
    assert not peg_mask(draw_scene(CALIB, None, HOLE), PerceptionConfig()).any()


def test_specks_below_min_area_are_ignored() -> None:
    img = draw_scene(CALIB, None, HOLE)
    img[20:24, 20:24] = (0, 230, 230)  # 16 px cyan speck
    assert measure(img, CALIB).peg is None


@pytest.mark.parametrize("rgb", [(220, 10, 45), (220, 35, 5)], ids=["hue-near-180", "hue-near-0"])
def test_red_hue_wraps_around(rgb: tuple[int, int, int]) -> None:
    img = draw_scene(CALIB, PegPose(y=0, z=5), HOLE, hole_rgb=rgb)
    assert measure(img, CALIB).hole is not None
    # Each range alone sees only its side of the wrap: both are needed.
    low_only = PerceptionConfig(hole_hsv=[HsvRange(lower=(0, 110, 40), upper=(10, 255, 255))])
    high_only = PerceptionConfig(hole_hsv=[HsvRange(lower=(170, 110, 40), upper=(180, 255, 255))])
    seen = [measure(img, CALIB, c).hole is not None for c in (low_only, high_only)]
    assert seen == ([False, True] if rgb[2] > rgb[1] else [True, False])


@pytest.mark.parametrize(("w", "h", "ppm"), [(64, 48, 0.4), (640, 480, 4.0), (321, 199, 1.7)])
def test_any_image_size(w: int, h: int, ppm: float) -> None:
    calib = default_calibration(w, h, ppm)
    peg = PegPose(y=3.0, z=-10.0, tilt_deg=7.0)
    m = measure(draw_scene(calib, peg, HOLE), calib, PerceptionConfig(min_area_px=10))
    left, right, _, _ = visible_box_mm(peg)
    assert m.peg.center_mm[0] == pytest.approx((left + right) / 2, abs=max(1.0, 1.5 / ppm))
    assert m.peg.tilt_deg == pytest.approx(7.0, abs=3.0 if ppm < 1 else 1.0)
    assert m.hole.center_mm[0] == pytest.approx(0.0, abs=max(1.0, 1.5 / ppm))


def test_board_surface_row_is_found() -> None:
    v = board_surface_v(draw_scene(CALIB, PegPose(y=0, z=-20), HOLE))
    assert v == pytest.approx(CALIB.to_pixel(0.0, 0.0)[1], abs=0.5)
    assert board_surface_v(np.zeros((50, 50, 3), np.uint8)) is None


def test_config_is_strict_and_overridable() -> None:
    cfg = apply_overrides(PerceptionConfig(), ["align_tol_mm=2.5", "tilt_tol_deg=4"])
    assert (cfg.align_tol_mm, cfg.tilt_tol_deg) == (2.5, 4.0)
    with pytest.raises(ConfigError):
        apply_overrides(PerceptionConfig(), ["align_tolerance=1"])


def test_rejects_non_rgb_input() -> None:
    with pytest.raises(ValueError, match="RGB"):
        measure(np.zeros((10, 10), np.uint8), CALIB)


def test_hole_split_by_the_peg_in_front_keeps_its_centre() -> None:
    img = draw_scene(CALIB, None, HoleGeom(y=5.0, depth_mm=30.0))
    u0, _ = CALIB.to_pixel(5.0, 0.0)
    img[150:240, int(u0) - 30 : int(u0) - 10] = (0, 230, 230)  # cyan bar cutting the red face in two
    m = measure(img, CALIB)
    assert m.hole.center_mm[0] == pytest.approx(5.0, abs=0.6)
    assert m.hole.right_mm - m.hole.left_mm == pytest.approx(42.0, abs=1.0)
