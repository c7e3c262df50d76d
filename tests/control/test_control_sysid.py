"""System identification on the pusher+box scene: a wrong prior is pulled back to the truth from logs."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from kintsugi.control.params import get_param
from kintsugi.control.rollout import get_state
from kintsugi.control.sysid import ExecutionLog, ParamSpec, Signal, SysIdConfig, SysIdProblem, fit, identify
from kintsugi.core.errors import ConfigError
from tests.control_fixtures import pusher_box

TRUTH = {"mass:box": 0.5, "friction:box": 0.5}
SPECS = [ParamSpec(kind="mass", name="box", bounds=(0.05, 8.0)),
         ParamSpec(kind="friction", name="box", bounds=(0.05, 2.0), against="table")]
SIGNALS = [Signal(sensor="box_pos", scale=0.01), Signal(sensor="fx", scale=0.2)]


def _log(seed: int, steps: int = 100) -> ExecutionLog:
    """Push the box (accelerate, cruise, stop so it slides out) in the TRUE world and log what sensors saw.

    The acceleration shows the mass in the force; the slide after the pusher stops shows the friction.
    """
    model, data = pusher_box(box_mass=TRUTH["mass:box"], box_friction=TRUTH["friction:box"])
    rng = np.random.default_rng(seed)
    start = get_state(model, data)
    speed, stop = rng.uniform(0.5, 0.8), min(steps - 1, int(rng.integers(35, 50)))
    t = np.arange(1, steps + 1) * model.opt.timestep
    controls = np.zeros((steps, 2))
    controls[:, 0] = speed * np.minimum(t, t[stop])
    controls[:, 1] = rng.uniform(-0.01, 0.01)
    box, fx = [], []
    for u in controls:
        data.ctrl[:] = u
        mujoco.mj_step(model, data)
        box.append(data.sensordata[0:3].copy())
        fx.append(data.sensordata[6:7].copy())
    return ExecutionLog(initial_state=start, controls=controls, observed={"box_pos": np.array(box), "fx": np.array(fx)},
                        dt=float(model.opt.timestep))


def _prior_model() -> mujoco.MjModel:
    model, _ = pusher_box(box_mass=TRUTH["mass:box"] * 8, box_friction=TRUTH["friction:box"] * 1.8)
    return model


def test_fit_recovers_mass_and_friction_from_an_8x_1_8x_prior() -> None:
    model = _prior_model()
    result = fit(SysIdProblem(model, SPECS, SIGNALS, [_log(0), _log(1)], SysIdConfig(grid=7, max_evals=40, nthread=2)))
    err = result.scored(TRUTH).relative_error
    assert err["mass:box"] < 0.1 and err["friction:box"] < 0.1, result.params
    assert result.loss < 0.01 * result.prior_loss
    assert get_param(model, "mass", "box") == pytest.approx(4.0)  # the fit leaves the model alone
    result.apply(model)
    assert get_param(model, "mass", "box") == pytest.approx(result.params["mass:box"])


def test_identify_cycles_write_beliefs_and_stop_when_converged() -> None:
    model = _prior_model()
    result = identify(model, SPECS, SIGNALS, _log, SysIdConfig(grid=7, zoom_rounds=1, max_evals=30, max_cycles=4,
                                                               converge_tol=0.05, nthread=2))
    assert 2 <= result.cycles <= 4 and len(result.history) == result.cycles
    assert result.prior == {"mass:box": pytest.approx(4.0), "friction:box": pytest.approx(0.9)}
    assert get_param(model, "mass", "box") == pytest.approx(result.params["mass:box"])
    err = result.scored(TRUTH).relative_error
    assert max(err.values()) < 0.1, result.params


def test_bad_problems_are_refused_with_names() -> None:
    model = _prior_model()
    log = _log(0, steps=10)
    with pytest.raises(ConfigError, match="not a sensor.*box_pos"):
        fit(SysIdProblem(model, SPECS, [Signal(sensor="nope")], [log]))
    with pytest.raises(ConfigError, match="at least one parameter"):
        fit(SysIdProblem(model, [], SIGNALS, [log]))
    model.geom_priority[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "table")] = 3
    with pytest.raises(ConfigError, match="higher geom priority"):
        fit(SysIdProblem(model, SPECS, SIGNALS, [log]))
    with pytest.raises(ValueError, match="0 < low < high"):
        ParamSpec(kind="mass", name="box", bounds=(1.0, 0.5))


def test_window_cap_counts_each_log_in_full_up_to_the_cap_then_one_percent_of_the_excess() -> None:
    from kintsugi.control.sysid import _Replay

    model = _prior_model()
    logs = [_log(0), _log(1)]
    settings = [np.array([4.0, 0.9]), np.array([0.5, 0.5]), np.array([0.6, 0.45])]
    plain = _Replay(SysIdProblem(model, SPECS, SIGNALS, logs[:1], SysIdConfig(nthread=1)))
    capped = _Replay(SysIdProblem(model, SPECS, SIGNALS, logs[:1], SysIdConfig(nthread=1, window_cap=1.0)))
    raw = plain.losses([plain.variant(x) for x in settings])
    got = capped.losses([capped.variant(x) for x in settings])
    np.testing.assert_allclose(got, np.minimum(raw, 1.0) + 0.01 * np.maximum(raw - 1.0, 0.0), rtol=1e-12)
    assert raw[0] > 1.0 and got[0] < raw[0] and raw[1] < 1e-6 and got[1] == pytest.approx(raw[1])
    assert np.argsort(got).tolist() == np.argsort(raw).tolist()  # far-off settings stay ranked
    plain.engine.close()
    capped.engine.close()
