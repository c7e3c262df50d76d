"""One attempt of a staged MPPI cost on the robot: observe -> stage machine -> plan -> act.

The planner sees only the planning world (beliefs) synced from the robot's observation;
stage transitions are judged on observations. Every stage the machine leaves becomes a
`SkillLog` of the trial; the planner's per-step statistics are kept for plots and videos.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from kintsugi.control import MPPI, MPPIConfig
from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.methods.mppi.costs import View
from kintsugi.methods.mppi.fsm import Guard, Stage, StageFactory, StageMachine, Transition
from kintsugi.worlds.contact.plot import PlanSeries
from kintsugi.worlds.contact.robot import ContactRobot, Observation
from kintsugi.worlds.contact.scene import ACTUATORS
from kintsugi.worlds.contact.world import PlanningWorld
from kintsugi.core.record import SkillLog
from kintsugi.core.log import TrialLog

GRIP = ACTUATORS.index("grip")


def observation_seed(obs: Observation) -> int:
    """A planner seed from what the robot first observes (its pose and the tracked objects' poses): a trial
    replays exactly and trials differ, without the trial's own seed (which would re-draw the truth)."""
    parts = [np.round(obs.ee, 6).tobytes()]
    parts += [np.round(np.concatenate([o.pos, o.quat]), 6).tobytes() for _, o in sorted(obs.objects.items())]
    return zlib.crc32(b"".join(parts)) % 1_000_000


@dataclass
class PlanTrace(PlanSeries):
    """The planner statistics (PlanSeries) plus, per step, the best predicted TCP path and the iteration time."""

    best_tcp: list[np.ndarray] = field(default_factory=list)
    iteration_s: list[float] = field(default_factory=list)
    rollout_s: list[float] = field(default_factory=list)


@dataclass
class AttemptResult:
    reached: bool
    """The machine ran through every stage (the method's own verdict, not the ground truth)."""
    stages: list[Transition]
    obs: Observation
    broken: str | None = None
    """Why a path constraint (a guard) failed the attempt, if one did."""


def mppi_config(cfg: ContactConfig, seed: int) -> MPPIConfig:
    c = cfg.control
    return MPPIConfig(samples=c.samples, horizon_s=c.horizon_s, knots=c.knots, noise_frac=c.noise_frac,
                      noise_ramp=c.noise_ramp, ess_fraction=c.ess_fraction, nthread=c.nthread, seed=seed)


class StagedPlanner:
    """MPPI on a planning world, driven by a stage machine; one instance per attempt."""

    def __init__(self, cfg: ContactConfig, planning: PlanningWorld, seed: int, skills_before: int = 0,
                 show: Callable[[np.ndarray, np.ndarray], None] | None = None,
                 stats: Callable[[float, str, float, float, float], None] | None = None) -> None:
        self.cfg = cfg
        self._show = show
        self._stats = stats
        self._skills0 = skills_before
        self.planning = planning
        self._obs: Observation | None = None
        self._stage: Stage | None = None
        self.mppi = MPPI(planning.model, mppi_config(cfg, seed), self._cost)
        self.trace = PlanTrace()

    def close(self) -> None:
        self.mppi.close()

    def _cost(self, batch) -> np.ndarray:  # noqa: ANN001 - a RolloutBatch
        assert self._stage is not None and self._obs is not None
        return self._stage.cost(View(batch, self.planning.layout, self._obs))

    def run(self, robot: ContactRobot, factories: list[StageFactory], budget_s: float, log: TrialLog,
            guards: tuple[Guard, ...] = ()) -> AttemptResult:
        machine = StageMachine(factories, guards)
        period = 1.0 / self.cfg.control.rate_hz
        obs = robot.observe()
        t_end = obs.t + budget_s
        while True:
            if machine.update(obs):
                self._report(machine, log)
                if machine.stage is not None:
                    self._enter(machine.stage, obs, log)
            if machine.finished or obs.t >= t_end - 1e-9:
                break
            stage = machine.stage
            assert stage is not None
            self._obs = obs
            data = self.planning.sync(obs.ee, obs.ee_vel, obs.fingers, obs.finger_vel,
                                      {k: (o.pos, o.quat, o.lin_vel, o.ang_vel) for k, o in obs.objects.items()},
                                      obs.ctrl, obs.t)
            self.mppi.step(data)
            self._record(stage, obs)
            obs = robot.act(self.mppi.action_at, min(period, t_end - obs.t), feedback=stage.feedback,
                            on_tick=machine.watch if stage.hold_s > 0 or guards else None)
        machine.close(obs)
        self._report(machine, log)
        return AttemptResult(reached=machine.succeeded, stages=list(machine.history), obs=obs, broken=machine.broken)

    def _enter(self, stage: Stage, obs: Observation, log: TrialLog) -> None:
        self._stage = stage
        self.mppi.pin(GRIP, stage.grip)
        self.mppi.set_noise_scale(stage.noise_scale)
        if self.mppi.nominal is not None:
            for i, v in stage.seed_plan.items():
                self.mppi.hold(i, v)
        log.status(stage.name)
        log.event(obs.t, "stage", f"{stage.name} {_fmt(stage.goal)}")

    def _record(self, stage: Stage, obs: Observation) -> None:
        s, tr = self.mppi.last, self.trace
        tr.add(obs.t, stage.name, s.cost_min, s.temperature, s.ess / max(1, s.n_valid))
        if self._stats is not None:
            self._stats(obs.t, stage.name, tr.cost[-1], tr.temperature[-1], tr.ess_frac[-1])
        batch = self.mppi.last_batch
        if batch is not None and s.best_index >= 0:
            tr.best_tcp.append(batch.sensor("tcp_pos")[s.best_index].copy())
            if self._show is not None:
                pts = [a.world_targets(obs.objects[a.region.obj].pos, obs.objects[a.region.obj].quat)
                       for a in stage.attractors]
                self._show(tr.best_tcp[-1], np.concatenate(pts) if pts else np.zeros((0, 3)))
        tr.iteration_s.append(s.total_s)
        tr.rollout_s.append(s.rollout_s)

    def _report(self, machine: StageMachine, log: TrialLog) -> None:
        """Log the stages the machine has left since the last report."""
        for tr in machine.history[len(log.skills) - self._skills0:]:
            log.skill(SkillLog(skill=tr.stage, goal={k: round(v, 4) for k, v in tr.goal.items()},
                               terminal={a: round(float(v) * 1000, 2) for a, v in zip("xyz", tr.ee[:3])},
                               reached=tr.reached, timed_out=not tr.reached and not tr.why, message=tr.why,
                               sim_time=round(tr.t_exit, 4)))
            log.event(tr.t_exit, "stage done" if tr.reached else "stage failed",
                      f"{tr.stage}: {tr.why}" if tr.why else tr.stage)


def _fmt(goal: dict[str, float]) -> str:
    return " ".join(f"{k}={v:.3g}" for k, v in goal.items())


def run_attempt(cfg: ContactConfig, robot: ContactRobot, planning: PlanningWorld, factories: list[StageFactory],
                log: TrialLog, seed: int, budget_s: float | None = None,
                guards: tuple[Guard, ...] = ()) -> tuple[AttemptResult, PlanTrace]:
    """Plan and act through `factories` until they finish, a guard breaks or the attempt's time budget runs out."""
    planner = StagedPlanner(cfg, planning, seed, skills_before=len(log.skills), show=robot.show_plan,
                             stats=getattr(robot, "plan_stats", None))
    try:
        result = planner.run(robot, factories, budget_s or cfg.control.episode_s, log, guards)
    finally:
        planner.close()
    return result, planner.trace
