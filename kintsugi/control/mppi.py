"""MPPI over spline knots with the temperature set by an effective-sample-size target.

Task-free: the caller supplies the planning model (its parameters are beliefs) and a cost
over a `RolloutBatch`. Each `step` time-shifts the previous plan to now (warm start), keeps
it unperturbed as sample 0, perturbs the other samples' knots with noise that grows toward
the end of the horizon (early knots were already optimised by earlier steps), rolls all
samples out in one batch, weights them (CoRAL S1-B) and returns the first action.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np
from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.control import spline
from kintsugi.control.feedback import ForceFeedbackConfig, force_feedback
from kintsugi.control.rollout import RolloutBatch, RolloutEngine
from kintsugi.control.temperature import mppi_weights, temperature_for_ess
from kintsugi.core.errors import ConfigError

__all__ = [
    "CostFn", "ForceFeedbackConfig", "IterationStats", "MPPI", "MPPIConfig",
    "force_feedback", "mppi_weights", "temperature_for_ess",
]

CostFn = Callable[[RolloutBatch], np.ndarray]
"""(K,) total cost of each rollout; may switch stages on the batch's states (caller's logic)."""


class MPPIConfig(StrictModel):
    samples: int = Field(256, ge=2)
    horizon_s: float = Field(0.5, gt=0)
    knots: int = Field(4, ge=1)
    interp: spline.Interp = "cubic"
    noise_frac: float = Field(0.1, ge=0)  # std at the first knot, fraction of each ctrlrange width
    noise_ramp: float = Field(2.0, ge=0)  # std multiplier at the last knot (linear in between)
    ess_fraction: float = Field(0.1, gt=0, le=1)
    iterations: int = Field(1, ge=1)  # planning iterations per step (same state)
    nthread: int | None = Field(None, ge=1)  # None: all cores
    seed: int = 0


@dataclass
class IterationStats:
    """What the last `step` saw; enough to plot cost, temperature and ESS over time."""

    cost_min: float = float("inf")
    cost_mean: float = float("inf")  # over valid samples
    cost_nominal: float = float("inf")  # sample 0: the warm-started plan
    temperature: float = float("nan")
    ess: float = 0.0  # effective sample size (a count)
    n_valid: int = 0
    best_qpos: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (T, nq) lowest-cost rollout
    best_index: int = -1  # its sample index in `MPPI.last_batch` (-1: none valid)
    rollout_s: float = 0.0  # physics: RolloutEngine.run, summed over iterations
    total_s: float = 0.0  # the whole step


class MPPI:
    """Receding-horizon MPPI on one planning model shared by every sample."""

    def __init__(self, model: mujoco.MjModel, cfg: MPPIConfig, cost: CostFn) -> None:
        limited = model.actuator_ctrllimited.astype(bool)
        if model.nu == 0 or not limited.all():
            names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) or str(i)
                     for i in np.flatnonzero(~limited)]
            raise ConfigError(
                "MPPI needs every actuator to have a ctrlrange (noise is a fraction of it); "
                f"unlimited: {', '.join(names) or '(the model has no actuators)'}"
            )
        self.model = model
        self.cfg = cfg
        self.cost = cost
        self.engine = RolloutEngine(model, cfg.nthread)
        dt = float(model.opt.timestep)
        self.steps = max(1, int(round(cfg.horizon_s / dt)))
        self.knot_offsets = np.linspace(0.0, self.steps * dt, cfg.knots) if cfg.knots > 1 else np.zeros(1)
        self._basis = spline.basis(cfg.interp, self.knot_offsets, np.arange(self.steps) * dt)
        self.ctrlrange = model.actuator_ctrlrange.copy()
        width = self.ctrlrange[:, 1] - self.ctrlrange[:, 0]
        ramp = np.linspace(1.0, cfg.noise_ramp, cfg.knots) if cfg.knots > 1 else np.ones(1)
        self._sigma0 = cfg.noise_frac * ramp[:, None] * width[None, :]  # (knots, nu)
        self._sigma = self._sigma0.copy()
        self.last = IterationStats()
        self.last_batch: RolloutBatch | None = None
        self._pinned: dict[int, float] = {}
        self.reset()

    # -- public -------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the plan and restart the noise stream (same seed -> same decisions)."""
        self._rng = np.random.default_rng(self.cfg.seed)
        self.nominal: np.ndarray | None = None  # (knots, nu)
        self.nominal_t0 = 0.0

    def set_cost(self, cost: CostFn) -> None:
        """Swap the cost (a new stage, a rewritten cost); the plan stays as a warm start."""
        self.cost = cost

    def pin(self, actuator: int, value: float | None) -> None:
        """Hold one actuator's command at `value` in every sample and in the plan (None: plan it again).

        A staged cost that decides the gripper itself (open to reach, closed to lift) pins it,
        so no sample wastes its noise on a command that will not be sent.
        """
        if not 0 <= actuator < self.model.nu:
            raise ConfigError(f"actuator index {actuator} out of range (the model has {self.model.nu})")
        if value is None:
            self._pinned.pop(actuator, None)
            return
        lo, hi = self.ctrlrange[actuator]
        self._pinned[actuator] = float(np.clip(value, lo, hi))
        if self.nominal is not None:
            self.nominal[:, actuator] = self._pinned[actuator]

    def hold(self, actuator: int, value: float) -> None:
        """Reset one actuator's planned command to a constant (the plan is re-optimised from there).

        A saturated actuator (a servo pressing at its force limit) makes every nearby sample
        cost the same; re-seeding the plan where the gradient is takes it out of that plateau.
        """
        if self.nominal is None:
            raise ConfigError("no plan yet: call step() first")
        lo, hi = self.ctrlrange[actuator]
        self.nominal[:, actuator] = float(np.clip(value, lo, hi))

    def set_noise_scale(self, scale: float) -> None:
        """Scale the sampling noise (e.g. fine force regulation wants millimetres, reaching centimetres)."""
        if not np.isfinite(scale) or scale < 0:
            raise ConfigError(f"noise scale must be a finite number >= 0, got {scale}")
        self._sigma = self._sigma0 * scale

    def close(self) -> None:
        self.engine.close()

    def step(self, data: mujoco.MjData) -> np.ndarray:
        """One planning step from `data` (planning-world copy of the measured state) -> action (nu,)."""
        t_start = time.perf_counter()
        self._warm_start(data)
        stats = IterationStats()
        for _ in range(self.cfg.iterations):
            self._iterate(data, stats)
        stats.total_s = time.perf_counter() - t_start
        self.last = stats
        return self.nominal[0].copy()

    def action_at(self, t: float) -> np.ndarray:
        """The current plan's command at absolute time t (held beyond the horizon)."""
        if self.nominal is None:
            raise ConfigError("no plan yet: call step() first")
        return spline.evaluate(self.cfg.interp, self.nominal_t0 + self.knot_offsets, self.nominal, np.array([t]))[0]

    def controls_for(self, knots: np.ndarray) -> np.ndarray:
        """(K, knots, nu) knot values -> (K, T, nu) per-step controls, clipped to ctrlrange."""
        u = np.einsum("tk,bkn->btn", self._basis, knots)
        return np.clip(u, self.ctrlrange[:, 0], self.ctrlrange[:, 1])

    # -- internals ----------------------------------------------------------------------
    def _warm_start(self, data: mujoco.MjData) -> None:
        t = float(data.time)
        if self.nominal is None:
            hold = np.clip(data.ctrl, self.ctrlrange[:, 0], self.ctrlrange[:, 1])
            self.nominal = np.tile(hold, (self.cfg.knots, 1))
        else:  # time-shift: the old spline evaluated at the new knot times
            old_t = self.nominal_t0 + self.knot_offsets
            self.nominal = spline.evaluate(self.cfg.interp, old_t, self.nominal, t + self.knot_offsets)
        for i, v in self._pinned.items():
            self.nominal[:, i] = v
        self.nominal_t0 = t

    def _iterate(self, data: mujoco.MjData, stats: IterationStats) -> None:
        K = self.cfg.samples
        noise = self._rng.standard_normal((K, *self.nominal.shape)) * self._sigma
        noise[0] = 0.0  # sample 0 is the warm-started plan itself
        for i in self._pinned:
            noise[:, :, i] = 0.0
        knots = np.clip(self.nominal + noise, self.ctrlrange[:, 0], self.ctrlrange[:, 1])
        controls = self.controls_for(knots)
        t0 = time.perf_counter()
        batch = self.engine.run(data, controls)
        stats.rollout_s += time.perf_counter() - t0
        costs = self._costs(batch)
        lam, ess = temperature_for_ess(costs, self.cfg.ess_fraction)
        finite = np.isfinite(costs)
        stats.temperature, stats.ess, stats.n_valid = lam, ess, int(finite.sum())
        stats.cost_nominal = float(costs[0])
        self.last_batch = batch
        if not finite.any():
            return  # nothing trustworthy: keep the plan
        w = mppi_weights(costs, lam)
        self.nominal = np.tensordot(w, knots, axes=1)
        best = int(np.argmin(np.where(finite, costs, np.inf)))
        stats.cost_min = float(costs[best])
        stats.cost_mean = float(costs[finite].mean())
        stats.best_qpos = batch.qpos[best].copy()
        stats.best_index = best

    def _costs(self, batch: RolloutBatch) -> np.ndarray:
        with np.errstate(all="ignore"):  # invalid rollouts may hold NaN; they are masked below
            costs = np.asarray(self.cost(batch), dtype=float)
        if costs.shape != (batch.samples,):
            raise ConfigError(f"the cost returned shape {costs.shape}; it must return one value per sample ({batch.samples},)")
        costs = costs.copy()
        costs[~batch.valid | ~np.isfinite(costs)] = np.inf
        return costs
