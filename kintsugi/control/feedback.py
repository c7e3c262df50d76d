"""The reactive feedback term of CoRAL Eq. 5: u = u_mppi + K_f (f_desired - f_measured).

MPPI plans at ~10 Hz in a planning world whose beliefs can be wrong; a force error measured
by the robot's own sensor corrects the commanded action at the control rate in between.
"""

from __future__ import annotations

import numpy as np
from pydantic import field_validator

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError


class ForceFeedbackConfig(StrictModel):
    """Gain K_f (nu x n_force, action units per newton) and a bound on the correction."""

    gain: tuple[tuple[float, ...], ...]
    max_correction: float | None = None  # per action component, in action units; None = unbounded

    @field_validator("gain")
    @classmethod
    def _rectangular(cls, g: tuple[tuple[float, ...], ...]) -> tuple[tuple[float, ...], ...]:
        if not g or len({len(row) for row in g}) != 1 or not g[0]:
            raise ValueError("gain must be a non-empty nu x n_force matrix (equal-length rows)")
        return g


def force_feedback(
    action: np.ndarray,
    measured: np.ndarray,
    desired: np.ndarray,
    cfg: ForceFeedbackConfig,
    ctrlrange: np.ndarray | None = None,
) -> np.ndarray:
    """Eq. 5 correction of a commanded action; pure (returns a new array).

    `ctrlrange` (nu, 2), when given, keeps the corrected action inside the actuators' limits.
    """
    u = np.asarray(action, dtype=float)
    gain = np.asarray(cfg.gain, dtype=float)
    err = np.asarray(desired, dtype=float) - np.asarray(measured, dtype=float)
    if gain.shape != (u.shape[-1], err.shape[-1]):
        raise ConfigError(
            f"feedback gain is {gain.shape[0]}x{gain.shape[1]} but the action has {u.shape[-1]} "
            f"components and the force error {err.shape[-1]}"
        )
    corr = gain @ err
    if cfg.max_correction is not None:
        corr = np.clip(corr, -cfg.max_correction, cfg.max_correction)
    out = u + corr
    if ctrlrange is not None:
        out = np.clip(out, ctrlrange[:, 0], ctrlrange[:, 1])
    return out
