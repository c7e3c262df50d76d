"""Randomized trial conditions: seed + condition -> the trial's hidden truth."""

from __future__ import annotations

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.peg.config import CONDITIONS, PegTaskConfig
from kintsugi.worlds.peg.world import TrialParams


def sample_params(cfg: PegTaskConfig, shape: str, condition: str, seed: int) -> TrialParams:
    """Draw every random value in a fixed order whatever the condition, so trial i of
    `pose` and of `all` share the same hole offset and grasp angle (paired comparison).
    The x offset is drawn last, so enabling it leaves every earlier draw unchanged."""
    if condition not in CONDITIONS:
        raise ConfigError(f"unknown condition {condition!r}; known: {', '.join(CONDITIONS)}")
    rng = np.random.default_rng(seed)
    hole_y = float(rng.uniform(*cfg.hole.y_offset_mm))
    angle = float(rng.uniform(*cfg.grasp.angle_deg))
    friction = float(rng.uniform(*cfg.hole.friction_scale))
    hole_x = float(rng.uniform(*cfg.hole.x_offset_mm))
    pose = condition in ("pose", "all")
    fric = condition in ("friction", "all")
    return TrialParams(
        shape=shape,
        hole_y_mm=hole_y if pose else 0.0,
        hole_x_mm=hole_x if pose else 0.0,
        grasp_angle_deg=angle if pose else 0.0,
        friction_scale=friction if fric else 1.0,
    )
