"""Every world's step ends in `kintsugi.core.health.check_health`: a diverging simulation is a clear error."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from kintsugi.core.errors import SimulationDiverged
from kintsugi.core.health import check_health

BALL = "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>"


def test_a_healthy_step_passes_and_a_non_finite_state_is_named() -> None:
    model = mujoco.MjModel.from_xml_string(BALL)
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data)
    check_health(data)
    data.qvel[0] = np.nan
    with pytest.raises(SimulationDiverged, match="non-finite state"):
        check_health(data)


def test_a_fatal_mujoco_warning_names_the_setting_to_change() -> None:
    model = mujoco.MjModel.from_xml_string(BALL)
    data = mujoco.MjData(model)
    data.qacc_warmstart[:] = 0
    data.qvel[2] = 1e12  # MuJoCo resets the state and warns BADQVEL
    mujoco.mj_step(model, data)
    with pytest.raises(SimulationDiverged, match="mjWARN_BADQ.*sim.timestep_s"):
        check_health(data)
