"""Task-free control: ESS temperature, MPPI on the pusher+box scene, rollout engine, Eq. 5 feedback, splines."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from kintsugi.control import MPPI, MPPIConfig, RolloutEngine, force_feedback, mppi_weights, temperature_for_ess
from kintsugi.control import spline
from kintsugi.control.feedback import ForceFeedbackConfig
from kintsugi.control.params import pair_friction, set_param
from kintsugi.core.errors import ConfigError, UnknownNameError
from tests.control_fixtures import pusher_box


def _ess(w: np.ndarray) -> float:
    return float(w.sum() ** 2 / (w * w).sum())


@pytest.mark.parametrize("fraction", [0.05, 0.1, 0.5, 0.9])
@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e4])
def test_temperature_hits_the_ess_target_whatever_the_cost_scale(fraction: float, scale: float) -> None:
    costs = np.random.default_rng(3).exponential(size=256) * scale
    lam, ess = temperature_for_ess(costs, fraction)
    w = mppi_weights(costs, lam)
    assert abs(_ess(w) - fraction * 256) < 0.01 * 256
    assert ess == pytest.approx(_ess(w), rel=1e-6)


def test_invalid_costs_get_zero_weight_and_do_not_count() -> None:
    costs = np.random.default_rng(0).uniform(size=100)
    costs[:40] = np.inf
    costs[40] = np.nan
    lam, ess = temperature_for_ess(costs, 0.5)
    w = mppi_weights(costs, lam)
    assert np.all(w[:41] == 0) and w.sum() == pytest.approx(1.0)
    assert ess == pytest.approx(0.5 * 59, rel=0.02)
    assert temperature_for_ess(np.full(5, np.inf), 0.1) == (float("inf"), 0.0)
    assert not mppi_weights(np.full(5, np.inf), 1.0).any()
    with pytest.raises(ConfigError, match="ess_fraction"):
        temperature_for_ess(costs, 0.0)


def test_spline_basis_is_linear_and_holds_beyond_the_knots() -> None:
    kt = np.array([0.0, 0.1, 0.2, 0.3])
    q = np.linspace(-0.1, 0.5, 25)
    vals = np.random.default_rng(1).normal(size=(4, 2))
    for kind in ("zero", "linear", "cubic"):
        out = spline.evaluate(kind, kt, vals, q)
        assert np.allclose(out[q <= 0], vals[0]) and np.allclose(out[q >= 0.3], vals[-1])
        assert np.allclose(spline.evaluate(kind, kt, 2 * vals, q), 2 * out)
    with pytest.raises(ValueError, match="unknown interpolation"):
        spline.basis("quintic", kt, q)  # type: ignore[arg-type]


def _to_target(target: np.ndarray):  # noqa: ANN202
    def cost(batch):  # noqa: ANN001, ANN202
        tip = batch.sensor("tip_pos")[:, :, :2]
        return np.linalg.norm(tip - target, axis=-1).mean(axis=1)

    return cost


def _drive(mppi: MPPI, model: mujoco.MjModel, data: mujoco.MjData, steps: int) -> list[np.ndarray]:
    actions = []
    for _ in range(steps):
        u = mppi.step(data)
        actions.append(u)
        data.ctrl[:] = u
        mujoco.mj_step(model, data, nstep=10)
    return actions


def test_mppi_reaches_a_target_and_replays_exactly_with_its_seed() -> None:
    target = np.array([-0.2, 0.15])
    runs = []
    for _ in range(2):
        model, data = pusher_box()
        mppi = MPPI(model, MPPIConfig(samples=64, horizon_s=0.4, knots=3, noise_frac=0.2, seed=5), _to_target(target))
        actions = _drive(mppi, model, data, 25)
        mppi.close()
        runs.append(np.array(actions))
        tip = data.sensordata[3:5]
        assert np.linalg.norm(tip - target) < 0.02, tip
        assert 0 < mppi.last.ess <= 64 and np.isfinite(mppi.last.temperature)
        assert mppi.last.best_qpos.shape == (40, model.nq) and 0 <= mppi.last.best_index < 64
    assert np.array_equal(runs[0], runs[1])


def test_nan_costs_never_poison_the_plan_and_pins_hold() -> None:
    model, data = pusher_box()
    target = np.array([0.0, 0.2])
    base = _to_target(target)

    def poisoned(batch):  # noqa: ANN001, ANN202
        c = base(batch)
        c[1::2] = np.nan  # half the samples report NaN
        return c

    mppi = MPPI(model, MPPIConfig(samples=32, horizon_s=0.3, knots=3, noise_frac=0.2, seed=1), poisoned)
    mppi.pin(0, 0.0)
    for _ in range(15):
        u = mppi.step(data)
        assert np.all(np.isfinite(u)) and u[0] == 0.0
        data.ctrl[:] = u
        mujoco.mj_step(model, data, nstep=10)
    assert mppi.last.n_valid == 16
    assert data.sensordata[4] > 0.1  # y still moved toward the target
    mppi.set_cost(lambda b: np.full(b.samples, np.nan))
    before, t_before = mppi.nominal.copy(), mppi.nominal_t0
    mppi.step(data)  # nothing valid: the plan is only time-shifted, never updated
    assert mppi.last.n_valid == 0 and np.allclose(mppi.nominal, spline.evaluate(
        "cubic", t_before + mppi.knot_offsets, before, mppi.nominal_t0 + mppi.knot_offsets))
    with pytest.raises(ConfigError, match="one value per sample"):
        mppi.set_cost(lambda b: np.zeros(3))
        mppi.step(data)
    with pytest.raises(ConfigError, match="out of range"):
        mppi.pin(7, 0.0)
    mppi.close()


def test_beliefs_written_into_the_shared_model_change_the_next_batch() -> None:
    model, data = pusher_box()
    engine = RolloutEngine(model, nthread=2)
    push = np.zeros((1, 60, 2))
    push[..., 0] = 0.4  # drive the pusher into the box and beyond
    light = engine.run(data, push).sensor("box_pos")[0, -1, 0]
    set_param(model, "mass", "box", 3.0)
    engine.refresh()
    batch = engine.run(data, push)
    heavy = batch.sensor("box_pos")[0, -1, 0]
    engine.close()
    assert light - heavy > 0.02, (light, heavy)
    with pytest.raises(UnknownNameError, match="box_pos"):
        batch.sensor("nope")


def test_diverging_rollouts_are_flagged_invalid() -> None:
    model, data = pusher_box()
    engine = RolloutEngine(model, nthread=1)
    data.qvel[0] = 1e30  # a state MuJoCo cannot integrate
    batch = engine.run(data, np.zeros((2, 5, 2)))
    engine.close()
    assert not batch.valid.any()
    with pytest.raises(ConfigError, match="controls must be"):
        RolloutEngine(model, 1).run(data, np.zeros((2, 5)))


def test_pair_friction_follows_mujoco_priority_then_max() -> None:
    model, _ = pusher_box(box_friction=0.5)
    assert pair_friction(model, "box", "table") == pytest.approx(0.5)
    model.geom_priority[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "table")] = 1
    assert pair_friction(model, "box", "table") == pytest.approx(0.1)


def test_force_feedback_corrects_clips_and_checks_shapes() -> None:
    cfg = ForceFeedbackConfig(gain=((0.01,), (0.0,)), max_correction=0.02)
    u = force_feedback(np.array([0.1, 0.2]), np.array([3.0]), np.array([5.0]), cfg)
    assert np.allclose(u, [0.12, 0.2])
    u = force_feedback(np.array([0.1, 0.2]), np.array([0.0]), np.array([50.0]), cfg, np.array([[0, 0.11], [0, 1]]))
    assert np.allclose(u, [0.11, 0.2])
    with pytest.raises(ConfigError, match="gain is 2x1"):
        force_feedback(np.zeros(3), np.zeros(1), np.zeros(1), cfg)
