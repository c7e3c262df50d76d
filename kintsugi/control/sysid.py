"""System identification: fit masses and frictions of a planning model to a logged execution.

The log holds what the robot knows: the measured initial state (as a planning-world state),
the controls it applied and measured trajectories of chosen sensors (object position from
perception, force readings). A candidate parameter setting is scored by replaying the
controls in the planning model and comparing the same sensors. The search is in
log-parameter space: a grid rolled out as ONE batched call (one model variant per sample,
`mujoco.rollout`'s model list), finer grids around the best point, then Nelder-Mead.

Friction: MuJoCo gives a contact pair the friction of the geom with the higher `priority`,
or the larger of the two when priorities are equal. So an object's friction is identified
*against a known surface* (`ParamSpec.against`): with equal priorities the search starts at
the surface's friction (below it the pair ignores the object's value and the loss is flat);
if the surface has the higher priority the object's friction is never used, and the problem
is refused.

Ground truth never enters a fit; `SysIdResult.scored(truth)` only measures the error.
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from pydantic import Field, field_validator, model_validator
from scipy.optimize import minimize

from kintsugi.core.config import StrictModel
from kintsugi.control import params as P
from kintsugi.control.rollout import RolloutEngine
from kintsugi.core.errors import ConfigError


class ParamSpec(StrictModel):
    """One unknown: the mass of a body or the sliding friction of a geom, searched within bounds."""

    kind: P.Kind
    name: str
    bounds: tuple[float, float]
    against: str | None = None  # friction only: the known surface geom the object slides on
    also: tuple[str, ...] = ()
    """Friction only: the object's other geoms, which share the value (an object built of several boxes)."""

    @field_validator("bounds")
    @classmethod
    def _positive(cls, b: tuple[float, float]) -> tuple[float, float]:
        if not 0 < b[0] < b[1]:
            raise ValueError(f"bounds must satisfy 0 < low < high, got {b}")
        return b

    @model_validator(mode="after")
    def _against_friction_only(self) -> ParamSpec:
        if self.against is not None and self.kind != "friction":
            raise ValueError("'against' names the surface of a friction parameter; a mass has none")
        if self.also and self.kind != "friction":
            raise ValueError("'also' names further geoms of a friction parameter; a mass is one body's")
        return self

    @property
    def key(self) -> str:
        return f"{self.kind}:{self.name}"


class Signal(StrictModel):
    """A sensor compared between log and replay; residuals are divided by `scale` (its units)."""

    sensor: str
    scale: float = Field(1.0, gt=0)
    weight: float = Field(1.0, ge=0)
    bin: int = Field(1, ge=1)
    """Compare means over bins of this many readings (contact spikes make single readings a rough loss)."""


class SysIdConfig(StrictModel):
    grid: int = Field(9, ge=3)  # log-spaced points per parameter, in every grid
    zoom_rounds: int = Field(2, ge=0)  # finer grids, each spanning +-1 step of the previous around its best
    max_evals: int = Field(60, ge=0)  # Nelder-Mead replays after the grids
    xatol: float = Field(2e-3, gt=0)  # in log(parameter): ~0.2 %
    max_cycles: int = Field(4, ge=1)
    converge_tol: float = Field(0.05, gt=0)  # stop when no parameter moved more than this (relative)
    nthread: int | None = Field(None, ge=1)
    window_cap: float | None = Field(None, gt=0)
    """Nearly truncated least squares: each log's loss counts in full up to this, and beyond it only
    `beyond_cap` of the excess (None: plain least squares). A contact-rich replay can diverge from its
    log whatever the parameters (a hand dragging on the table flips between stick and slip on a 1 %
    change); such a log says little beyond 'it diverged', and under a plain squared loss its chaotic
    few units would outweigh every log that does inform. The small slope keeps far-off settings ranked.
    Set it in the units of the signals' scales: about the loss of a log replayed with the right parameters."""
    beyond_cap: float = Field(0.01, ge=0, le=1)
    substeps: int = Field(1, ge=1)
    """Physics steps per logged control step in replays: a log at a coarse control rate can be replayed
    with a finer integration (each command held for `substeps` steps, sensors read at the log's rate)."""


@dataclass
class ExecutionLog:
    """One logged execution, one row per control step of `dt` seconds (replays step at `dt`).

    `observed[sensor]` is (N, dim): the reading after each of the N control steps; NaN marks
    a missing measurement (e.g. the object was occluded).
    """

    initial_state: np.ndarray  # FULLPHYSICS state of the planning model
    controls: np.ndarray  # (N, nu)
    observed: dict[str, np.ndarray]
    dt: float
    label: str = ""
    """The caller's note of what the log can inform (e.g. "slide"); the fit ignores it."""


@dataclass
class SysIdProblem:
    model: mujoco.MjModel  # the planning model (beliefs); fit() does not modify it
    params: list[ParamSpec]
    signals: list[Signal]
    logs: list[ExecutionLog]
    cfg: SysIdConfig = field(default_factory=SysIdConfig)


@dataclass
class SysIdResult:
    params: dict[str, float]  # ParamSpec.key -> fitted value
    prior: dict[str, float]  # the beliefs the fit started from
    loss: float
    prior_loss: float
    cycles: int = 1
    rollouts: int = 0  # replays run (grid + Nelder-Mead)
    history: list[dict[str, float]] = field(default_factory=list)  # fitted params after each cycle
    relative_error: dict[str, float] | None = None  # only from scored(truth)

    def apply(self, model: mujoco.MjModel) -> None:
        """Write the fitted beliefs into a planning model and re-derive its constants."""
        for key, value in self.params.items():
            kind, name = key.split(":", 1)
            P.set_param(model, kind, name, value)  # type: ignore[arg-type]
        P.commit(model)

    def scored(self, truth: dict[str, float]) -> SysIdResult:
        """A copy with |fit - truth| / truth per parameter (benchmarks only)."""
        missing = sorted(set(self.params) - set(truth))
        if missing:
            raise ConfigError(f"truth lacks {', '.join(missing)}")
        err = {k: abs(v - truth[k]) / abs(truth[k]) for k, v in self.params.items()}
        return replace(self, relative_error=err)


def search_bounds(model: mujoco.MjModel, spec: ParamSpec) -> tuple[float, float]:
    """The spec's bounds, with a friction's low end raised to where the object's value matters."""
    lo, hi = spec.bounds
    P.resolve(model, spec.kind, spec.name)
    if spec.kind != "friction" or spec.against is None:
        return lo, hi
    obj = P.resolve(model, "friction", spec.name)
    surf = P.resolve(model, "friction", spec.against)
    if model.geom_priority[surf] > model.geom_priority[obj]:
        raise ConfigError(
            f"friction of {spec.name!r} is not identifiable against {spec.against!r}: the surface has the "
            "higher geom priority, so contacts use its friction; raise the object's priority"
        )
    if model.geom_priority[obj] == model.geom_priority[surf]:
        mu_surf = float(model.geom_friction[surf, 0])
        if mu_surf >= hi:
            raise ConfigError(
                f"friction of {spec.name!r} is not identifiable against {spec.against!r}: the surface's "
                f"friction {mu_surf:g} is above the search range (MuJoCo uses the larger of a pair)"
            )
        lo = max(lo, mu_surf * 1.001)
    return lo, hi


class _Replay:
    """Scores parameter settings by replaying the logs in planning-model variants."""

    def __init__(self, problem: SysIdProblem) -> None:
        if not problem.params or not problem.logs or not problem.signals:
            raise ConfigError("system identification needs at least one parameter, one log and one signal")
        self.problem = problem
        dts = {round(log.dt, 12) for log in problem.logs}
        if len(dts) != 1:
            raise ConfigError(f"logs were sampled at different timesteps {sorted(dts)}; resample them to one")
        # replays step at the log's rate (a planner may use a coarser step; its contacts are cruder)
        self.model = copy.copy(problem.model)
        self.substeps = problem.cfg.substeps
        self.model.opt.timestep = problem.logs[0].dt / self.substeps
        self.engine = RolloutEngine(self.model, problem.cfg.nthread)
        self.scratch = mujoco.MjData(self.model)
        for i, log in enumerate(problem.logs):
            for s in problem.signals:
                if s.sensor not in self.engine.sensor_slices:
                    known = ", ".join(sorted(self.engine.sensor_slices)) or "(none)"
                    raise ConfigError(f"signal {s.sensor!r} is not a sensor of the planning model; sensors: {known}")
                if s.sensor not in log.observed:
                    raise ConfigError(f"log {i} has no readings of {s.sensor!r}")
                sl = self.engine.sensor_slices[s.sensor]
                shape = (len(log.controls), sl.stop - sl.start)
                if np.shape(log.observed[s.sensor]) != shape:
                    raise ConfigError(f"log {i}: {s.sensor!r} readings are {np.shape(log.observed[s.sensor])}, expected {shape}")
        # logs of equal length replay together: one batched call per length
        self.groups: dict[int, list[ExecutionLog]] = {}
        for log in problem.logs:
            self.groups.setdefault(len(log.controls), []).append(log)
        self.rollouts = 0

    def variant(self, values: np.ndarray, model: mujoco.MjModel | None = None) -> mujoco.MjModel:
        m = model if model is not None else copy.copy(self.model)
        for spec, v in zip(self.problem.params, values):
            for name in (spec.name, *spec.also):
                P.set_param(m, spec.kind, name, float(v))
        mujoco.mj_setConst(m, self.scratch)
        return m

    def losses(self, models: list[mujoco.MjModel]) -> np.ndarray:
        """Mean over logs of the weighted, scaled squared sensor residuals (each log's capped at
        `window_cap`); inf if a replay diverged numerically."""
        G = len(models)
        total = np.zeros(G)
        for logs in self.groups.values():
            L = len(logs)  # sample index = model * L + log
            states = np.repeat(np.stack([lg.initial_state for lg in logs])[None], G, axis=0).reshape(G * L, -1)
            controls = np.repeat(np.stack([lg.controls for lg in logs])[None], G, axis=0).reshape(G * L, *logs[0].controls.shape)
            controls = np.repeat(controls, self.substeps, axis=1)
            batch = self.engine.run_state(states, controls, models=[m for m in models for _ in range(L)])
            self.rollouts += G * L
            part = np.zeros(G * L)
            for s in self.problem.signals:
                obs = np.stack([lg.observed[s.sensor] for lg in logs])  # (L, N, dim)
                seen = batch.sensor(s.sensor)[:, self.substeps - 1::self.substeps].reshape(G, L, *obs.shape[1:])
                resid = (_binned(seen, s.bin) - _binned(obs[None], s.bin)) / s.scale
                with np.errstate(invalid="ignore"):
                    part += s.weight * np.nanmean(resid**2, axis=(2, 3)).reshape(G * L)
            if self.problem.cfg.window_cap is not None:
                cap = self.problem.cfg.window_cap
                part = np.minimum(part, cap) + self.problem.cfg.beyond_cap * np.maximum(part - cap, 0.0)
            part[~batch.valid] = np.inf
            total += part.reshape(G, L).sum(axis=1)
        total /= len(self.problem.logs)
        total[~np.isfinite(total)] = np.inf
        return total


def _binned(x: np.ndarray, size: int) -> np.ndarray:
    """(..., N, dim) -> (..., N // size, dim) means (a trailing partial bin is dropped); NaN-aware."""
    if size == 1:
        return x
    n = x.shape[-2] // size
    with np.errstate(invalid="ignore"), __import__("warnings").catch_warnings():
        __import__("warnings").simplefilter("ignore", RuntimeWarning)
        return np.nanmean(x[..., : n * size, :].reshape(*x.shape[:-2], n, size, x.shape[-1]), axis=-2)


def fit(problem: SysIdProblem) -> SysIdResult:
    """Log-spaced grid, zoomed grids around the best point, then Nelder-Mead; model untouched.

    Each grid is one batched replay (per log length). Contact makes the loss rough at the
    millimetre scale (stick-slip ends a slide a little earlier or later), so the batched
    grids do the global work and Nelder-Mead only polishes.
    """
    replay = _Replay(problem)
    try:
        return _search(problem, replay)
    finally:
        replay.engine.close()


def replay_loss(problem: SysIdProblem) -> float:
    """The loss of the model's own parameters on the logs: one batched replay, no search."""
    replay = _Replay(problem)
    try:
        values = np.array([P.get_param(problem.model, s.kind, s.name) for s in problem.params])
        return float(replay.losses([replay.variant(values)])[0])
    finally:
        replay.engine.close()


def _search(problem: SysIdProblem, replay: _Replay) -> SysIdResult:
    cfg = problem.cfg
    specs = problem.params
    bounds = [search_bounds(problem.model, s) for s in specs]
    lo = np.log([b[0] for b in bounds])
    hi = np.log([b[1] for b in bounds])
    prior = {s.key: P.get_param(problem.model, s.kind, s.name) for s in specs}
    prior_loss = float(replay.losses([replay.variant(np.array([prior[s.key] for s in specs]))])[0])

    def grid_search(centre_lo: np.ndarray, centre_hi: np.ndarray) -> tuple[np.ndarray, float]:
        axes = [np.linspace(a, b, cfg.grid) for a, b in zip(centre_lo, centre_hi)]
        pts = np.array(list(itertools.product(*axes)))
        loss = replay.losses([replay.variant(np.exp(x)) for x in pts])
        if not np.isfinite(loss).any():
            raise ConfigError("every replay on the parameter grid diverged; check the log's initial state and controls")
        i = int(np.argmin(loss))
        return pts[i], float(loss[i])

    best_x, best_loss = grid_search(lo, hi)
    half = (hi - lo) / (cfg.grid - 1)  # one grid step on each side of the best point
    for _ in range(cfg.zoom_rounds):
        x, loss = grid_search(np.maximum(lo, best_x - half), np.minimum(hi, best_x + half))
        if loss <= best_loss:
            best_x, best_loss = x, loss
        half = 2 * half / (cfg.grid - 1)

    if cfg.max_evals > 0:
        work = copy.copy(replay.model)

        def objective(x: np.ndarray) -> float:
            return float(replay.losses([replay.variant(np.exp(np.clip(x, lo, hi)), work)])[0])

        simplex = np.vstack([best_x] + [best_x + np.eye(len(best_x))[i] * half[i] for i in range(len(best_x))])
        res = minimize(
            objective, best_x, method="Nelder-Mead", bounds=list(zip(lo, hi)),
            options={"initial_simplex": np.clip(simplex, lo, hi), "maxfev": cfg.max_evals,
                     "xatol": cfg.xatol, "fatol": 1e-9},
        )
        if res.fun < best_loss:
            best_x, best_loss = np.clip(res.x, lo, hi), float(res.fun)
    fitted = {s.key: float(np.exp(x)) for s, x in zip(specs, best_x)}
    return SysIdResult(
        params=fitted, prior=prior, loss=best_loss, prior_loss=prior_loss,
        rollouts=replay.rollouts, history=[fitted],
    )


def identify(
    model: mujoco.MjModel,
    params: list[ParamSpec],
    signals: list[Signal],
    execute: Callable[[int], ExecutionLog],
    cfg: SysIdConfig | None = None,
) -> SysIdResult:
    """Cycles of execute -> fit on every log so far -> write beliefs into `model`.

    `execute(cycle)` runs one attempt in the evaluation world (planning with the current
    beliefs in `model`) and returns its log. Stops when no parameter moved more than
    `converge_tol` (relative) between two cycles, or after `max_cycles`.
    """
    cfg = cfg or SysIdConfig()
    prior = {s.key: P.get_param(model, s.kind, s.name) for s in params}
    logs: list[ExecutionLog] = []
    history: list[dict[str, float]] = []
    rollouts, first_prior_loss = 0, float("nan")
    result: SysIdResult | None = None
    for cycle in range(1, cfg.max_cycles + 1):
        logs.append(execute(cycle - 1))
        result = fit(SysIdProblem(model, params, signals, list(logs), cfg))
        if cycle == 1:
            first_prior_loss = result.prior_loss
        rollouts += result.rollouts
        result.apply(model)
        history.append(result.params)
        if cycle > 1 and all(
            abs(history[-1][k] - history[-2][k]) <= cfg.converge_tol * abs(history[-2][k]) for k in history[-1]
        ):
            break
    assert result is not None
    return replace(result, prior=prior, prior_loss=first_prior_loss, cycles=len(history),
                   rollouts=rollouts, history=history)
