"""Health of a MuJoCo simulation, shared by every world: a diverging step is an error, never a silent wrong result."""

from __future__ import annotations

import mujoco
import numpy as np

from kintsugi.core.errors import SimulationDiverged

FATAL_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQACC,
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_CONTACTFULL,
    mujoco.mjtWarning.mjWARN_CNSTRFULL,
)
_FATAL_INDEX = np.array([int(w) for w in FATAL_WARNINGS])


def check_health(data: mujoco.MjData) -> None:
    """Raise SimulationDiverged on a fatal MuJoCo warning or a non-finite state, naming what to change."""
    counts = data.warning.number[_FATAL_INDEX]
    if counts.any():
        w = FATAL_WARNINGS[int(np.flatnonzero(counts)[0])]
        raise SimulationDiverged(f"MuJoCo warning {w.name} at t={data.time:.3f}s; "
                                 "lower sim.timestep_s or raise sim.contact_timeconst_s")
    if not np.isfinite(data.qpos).all() or not np.isfinite(data.qvel).all():
        raise SimulationDiverged(f"non-finite state at t={data.time:.3f}s")
