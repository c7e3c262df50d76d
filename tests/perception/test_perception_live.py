"""Perception on a frame rendered live by PegWorld (skipped only while the world module is absent)."""

from __future__ import annotations

import math
import os

os.environ.setdefault("MUJOCO_GL", "egl")  # headless; must precede the first `import mujoco`

import mujoco
import numpy as np
import pytest

world_mod = pytest.importorskip("kintsugi.worlds.peg.world")

from kintsugi.perception import align_check, measure  # noqa: E402


def test_live_render_tilt_and_hole() -> None:
    from kintsugi.worlds.peg.config import PegTaskConfig

    world = world_mod.PegWorld(PegTaskConfig(), world_mod.TrialParams(shape="round", hole_y_mm=8.0, grasp_angle_deg=4.0))
    try:
        # Peg hanging in the air 20 mm above the board, base rolled by 6 degrees: no contact, exact tilt.
        world.set_base(np.array([0.0, 0.16, math.radians(6.0)]))
        world.step(200)
        m = measure(world.render(), world.calibration())
        peg = mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_BODY, "peg")
        up = world.data.xmat[peg].reshape(3, 3)[:, 2]  # peg axis toward its top
        truth = math.degrees(math.atan2(-up[1], up[2]))  # + when the top is toward -y (image left)
    finally:
        world.close()
    assert m.peg is not None and m.hole is not None
    # Roll about +x tips the peg's lower end toward +y: its top leans left, positive tilt
    # (a little under 6 + 4 degrees: gravity bends the soft roll hinge back).
    assert 5.0 < truth < 10.0
    assert m.peg.tilt_deg == pytest.approx(truth, abs=0.5)
    assert m.hole.center_mm[0] == pytest.approx(8.0, abs=0.5)
    # The hanging peg's visible part swings to the right of the hole centre.
    assert m.peg.center_mm[0] - m.hole.center_mm[0] > 3.0
    assert align_check(m).message == "p_gy was too big. also tilted to the left."
