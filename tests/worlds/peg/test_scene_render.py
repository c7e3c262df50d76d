"""The camera shows the hole where it is: the red rim spans the opening for every shape."""

from __future__ import annotations

import pytest

import kintsugi  # noqa: F401 - MUJOCO_GL before mujoco
from kintsugi.perception.segment import measure
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.world import PegWorld, TrialParams

CFG = PegTaskConfig()


@pytest.mark.parametrize("shape", ["round", "square", "rectangle", "polygon3", "polygon5", "polygon6"])
@pytest.mark.parametrize("hole_y_mm", [0.0, 13.0])
def test_rim_in_image_spans_the_true_opening(shape: str, hole_y_mm: float) -> None:
    world = PegWorld(CFG, TrialParams(shape=shape, hole_y_mm=hole_y_mm))
    seen = measure(world.render(), world.calibration(), CFG.perception)
    y0, y1 = (v * 1000 + hole_y_mm for v in world.hole.y_range)
    px = 1 / world.calibration().px_per_mm
    assert seen.hole is not None
    assert seen.hole.left_mm == pytest.approx(y0, abs=px)
    assert seen.hole.right_mm == pytest.approx(y1, abs=px)
    world.close()
