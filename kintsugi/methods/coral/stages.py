"""A checked formulation (cost code + stages + regions) -> the stage factories the MPPI planner runs.

Each stage's cost calls the compiled program on the rollout batch (lazy variables), its
transition calls the `done` function on the measured state. A cost that returns NaN or inf
for a sample gives that sample no weight; a function that fails at run time, or overruns the
loop's bound (`kintsugi.sandbox.guard`: far longer than its probe measured, or than the loop's
budget), ends the attempt with a `CostCodeError` the method records (never silent, never a stall).

A stage whose cost function `c` has companions `c_seed_x`, `c_seed_y`, `c_seed_z` or `c_seed_yaw`
in the code (functions of the state at stage entry, one number each) restarts its plan's commands
on those axes from their values: MPPI refines from the stage's own goal instead of crawling there
from the previous stage's plan (the warm start the expert FSM gives its stages).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from kintsugi.control import ForceFeedbackConfig, force_feedback
from kintsugi.core.errors import KintsugiError, SandboxError
from kintsugi.methods.coral.env import entry_env, rollout_env, state_env, static_env
from kintsugi.methods.coral.types import FormulationReply, StageSpec, seed_functions
from kintsugi.sandbox import CostProgram
from kintsugi.methods.mppi.costs import Attractor, ContactRegion, View, total
from kintsugi.methods.mppi.fsm import Stage, StageFactory
from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.world import Scene

FB_GAIN = 0.6
"""Eq. 5 gain as a fraction of the servo's compliance (1 / kp): metres of command per newton of error."""


class CostCodeError(KintsugiError):
    """Cost code failed inside the control loop."""


@dataclass
class CodeTiming:
    """Seconds spent in cost code per planning step (for the < 10 % of an MPPI iteration budget)."""

    calls: int = 0
    seconds: float = 0.0
    per_call: list[float] = field(default_factory=list)


def attractor_of(reply: FormulationReply, index: int | None, samples: int, seed: int) -> Attractor | None:
    if index is None:
        return None
    r = reply.regions[index]
    return Attractor(ContactRegion(obj=r.object, center=r.center, normal=r.normal, radius=r.radius,
                                   standoff=r.standoff, drop=r.drop), samples, seed=seed)


def _truthy(value: np.ndarray) -> bool:
    a = np.asarray(value, dtype=float)
    return bool(a.size > 0 and np.all(np.isfinite(a)) and np.all(a != 0))


def build_stages(reply: FormulationReply, program: CostProgram, scene: Scene, cfg, seed: int,  # noqa: ANN001
                 timing: CodeTiming, first: dict[str, np.ndarray] | None = None) -> list[StageFactory]:
    """`first`: the `first_<object>_pos` constants, where each object was when the attempt began."""
    fixed = {**static_env(scene, cfg), **(first or {})}
    return [_factory(s, reply, program, scene, cfg, fixed, seed + i, timing) for i, s in enumerate(reply.stages)]


def _factory(spec: StageSpec, reply: FormulationReply, program: CostProgram, scene: Scene, cfg,  # noqa: ANN001
             fixed: dict, seed: int, timing: CodeTiming) -> StageFactory:
    attractor = attractor_of(reply, spec.region, cfg.control.attractor_samples, seed)

    def make(obs: Observation) -> Stage:
        env0 = {**fixed, **entry_env(obs, scene)}
        t0 = obs.t
        if spec.keep is not None:
            try:
                env0["kept"] = np.asarray(program.bounded_call(spec.keep, state_env(obs, scene, env0, None, 0.0)), dtype=float)
            except SandboxError as exc:
                raise CostCodeError(f"stage {spec.name} keep: {exc}") from None

        def cost(view: View) -> np.ndarray:
            start = time.perf_counter()
            try:
                k = view.tcp.shape[0]
                run = program.bounded_call(spec.cost, rollout_env(view, scene, env0, attractor), view.tcp.shape[:2])
            except SandboxError as exc:
                raise CostCodeError(f"stage {spec.name}: {exc}") from None
            out = total(run)
            out[~np.isfinite(out)] = np.inf
            dt = time.perf_counter() - start
            timing.calls += 1
            timing.seconds += dt
            if len(timing.per_call) < 5000:
                timing.per_call.append(dt)
            assert out.shape == (k,)
            return out

        def done(o: Observation) -> bool:
            try:
                return _truthy(program.bounded_call(spec.done, state_env(o, scene, env0, attractor, o.t - t0)))
            except SandboxError as exc:
                raise CostCodeError(f"stage {spec.name} transition: {exc}") from None

        return Stage(name=spec.name, cost=cost, done=done, grip=_grip(spec, program, obs, scene, env0, cfg),
                     timeout_s=spec.timeout_s, hold_s=spec.hold_s, feedback=_feedback(spec, cfg),
                     attractors=(attractor,) if attractor else (),
                     seed_plan={**_seed(spec, program, obs, scene, env0), **_preload(spec, obs, cfg)},
                     noise_scale=spec.noise_scale, goal=_goal(spec))

    return make


def _grip(spec: StageSpec, program: CostProgram, obs: Observation, scene: Scene, env0: dict, cfg  # noqa: ANN001
          ) -> float | None:
    g = spec.grip
    if isinstance(g, (int, float)):
        return float(g)
    if g == "open":
        return float(cfg.effector.max_opening_m)
    if g == "closed":
        return 0.0
    if g == "free":
        return None
    try:
        value = float(np.asarray(program.bounded_call(g, state_env(obs, scene, env0, None, 0.0)), dtype=float).ravel()[0])
    except (SandboxError, IndexError) as exc:
        raise CostCodeError(f"stage {spec.name} grip: {exc}") from None
    if not np.isfinite(value):
        raise CostCodeError(f"stage {spec.name} grip: {g}() is not finite")
    return float(np.clip(value, 0.0, cfg.effector.max_opening_m))


def _feedback(spec: StageSpec, cfg):  # noqa: ANN001, ANN202
    if spec.press_n is None:
        return None
    k = FB_GAIN / cfg.effector.kp_n_per_m
    gains = [(0.0,)] * 5
    gains[spec.press_axis] = (k,)
    fb = ForceFeedbackConfig(gain=tuple(gains), max_correction=0.01)
    axis, target = spec.press_axis, spec.press_n

    def apply(obs: Observation, planned: np.ndarray) -> np.ndarray:
        return force_feedback(planned, obs.force[axis:axis + 1], np.array([target]), fb)

    return apply


def _seed(spec: StageSpec, program: CostProgram, obs: Observation, scene: Scene, env0: dict) -> dict[int, float]:
    """The commands a stage's plan restarts from: for each axis whose `<cost>_seed_<axis>` function the code
    defines (x, y, z of the TCP in m, yaw in rad), that function's value at stage entry.

    A seed that fails or is not one finite number ends the attempt with a `CostCodeError`, like any function
    of the code that fails at run time."""
    out: dict[int, float] = {}
    for name, index in seed_functions(spec.cost, program.has).items():
        try:
            value = np.asarray(program.bounded_call(name, state_env(obs, scene, env0, None, 0.0)), dtype=float).ravel()
        except SandboxError as exc:
            raise CostCodeError(f"stage {spec.name} seed: {exc}") from None
        if value.size != 1 or not np.isfinite(value[0]):
            raise CostCodeError(f"stage {spec.name} seed: {name}() must return one finite number, "
                                f"got {value.size} values")
        out[index] = float(value[0])
    return out


def _preload(spec: StageSpec, obs: Observation, cfg) -> dict[int, float]:  # noqa: ANN001
    """A pressing stage restarts its plan from the command that springs the servo to the target force."""
    if spec.press_n is None:
        return {}
    return {spec.press_axis: float(obs.ee[spec.press_axis]) + spec.press_n / cfg.effector.kp_n_per_m}


def _goal(spec: StageSpec) -> dict[str, float]:
    goal = {"timeout_s": spec.timeout_s}
    if spec.press_n is not None:
        goal["force_n"] = spec.press_n
    if spec.hold_s:
        goal["hold_s"] = spec.hold_s
    return goal
