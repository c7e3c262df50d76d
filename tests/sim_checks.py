"""Assertions on a MuJoCo world shared by the physics tests: stricter than the product's `check_health`
(which raises only on fatal warnings), a test world must step without any warning at all."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np


def assert_no_warnings(world: Any) -> None:
    """No MuJoCo warning of any kind so far, and a finite state (`world.data` is the world's MjData)."""
    data = world.data
    counts = {mujoco.mjtWarning(i).name: int(data.warning[i].number)
              for i in range(mujoco.mjtWarning.mjNWARNING) if data.warning[i].number}
    assert not counts, counts
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()
