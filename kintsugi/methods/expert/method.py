"""System C's baseline methods: hand-written expert costs on MPPI, with and without a true world model.

- `expert`: one hand-written cost per task; planning world = the truth (oracle physics).
- `expert-fsm`: hand-written staged costs with transitions; planning world = the truth
  (the paper's upper bound).
- `mppi-sysid`: the expert-FSM costs, but the planning world starts from a wrong prior
  (each known model's volume at `sysid.prior_density_kg_m3`, friction `sysid.prior_friction`)
  and system identification corrects it from the logged attempt after each failure. It is not an
  oracle: no true physics, no trial seed, no ranges (its planner is seeded from its first observation).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from kintsugi.core.errors import ConfigError
from kintsugi.core.registry import METHODS
from kintsugi.core.log import TrialLog
from kintsugi.core.record import Figures

TAGS = ("system-c",)
ORACLE = ("system-c", "oracle-physics")


def _check(ctx: Any, name: str) -> None:
    from kintsugi.worlds.contact.context import ContactContext

    if not isinstance(ctx, ContactContext):
        raise ConfigError(f"method {name!r} runs the contact tasks (system C) only")


class Expert:
    """One attempt of a hand-written cost, planning in a world that holds the true physics."""

    def __init__(self, ctx: Any, staged: bool) -> None:
        from kintsugi.methods.expert.designs import expert_design

        if ctx.oracle_physics is None:
            raise ConfigError("the expert baselines plan in the true world: register them with the "
                              "'oracle-physics' tag")
        self.ctx = ctx
        self.design = expert_design(ctx.task.name, staged)

    def run(self, robot: Any, log: TrialLog) -> bool:
        from kintsugi.methods.mppi.execute import run_attempt
        from kintsugi.worlds.contact.world import PlanningWorld

        planning = PlanningWorld(self.ctx.cfg, self.ctx.known, self.ctx.oracle_physics)
        result, _ = run_attempt(self.ctx.cfg, robot, planning, self.design(self.ctx), log, seed=self.ctx.seed)
        return result.reached


@METHODS.register("expert", "system C: hand-written single-stage MPPI cost per task, planning world = truth",
                  tags=ORACLE)
def make_expert(ctx: Any, settings: object = None) -> Expert:
    _check(ctx, "expert")
    return Expert(ctx, staged=False)


@METHODS.register("expert-fsm", "system C: hand-written staged MPPI costs with transitions, planning world = truth "
                                "(the paper's upper bound)", tags=ORACLE)
def make_expert_fsm(ctx: Any, settings: object = None) -> Expert:
    _check(ctx, "expert-fsm")
    return Expert(ctx, staged=True)


class MPPISysId:
    """Expert-FSM costs on a planning world from a wrong prior, refitted after every failed attempt."""

    def __init__(self, ctx: Any) -> None:
        from kintsugi.methods.expert.designs import expert_design

        self.ctx = ctx
        self.design = expert_design(ctx.task.name, staged=True)
        self.history: list[dict[str, float]] = []
        self._seed = 0

    def prior(self) -> dict[str, Any]:
        """Each object's known-model volume at the configured density, and the configured friction: a prior from
        the shape alone, never the trial's truth or its ranges."""
        from kintsugi.worlds.contact.objects import Physics

        s = self.ctx.cfg.sysid
        lo, hi = s.mass_bounds_kg
        return {k: Physics(mass_kg=min(hi, max(lo, sum(g.volumes) * s.prior_density_kg_m3)), friction=s.prior_friction)
                for k, g in self.ctx.known.geometry.items()}

    def run(self, robot: Any, log: TrialLog) -> bool:
        from kintsugi.methods.mppi.execute import observation_seed
        from kintsugi.methods.mppi.identify import BeliefFitter
        from kintsugi.worlds.contact.world import PlanningWorld

        cfg, obj = self.ctx.cfg, self.ctx.task.target
        self._seed = observation_seed(robot.observe())
        self._design_ctx = replace(self.ctx, seed=self._seed)  # the expert designs seed their contact samples
        planning = PlanningWorld(cfg, self.ctx.known, self.prior())
        fitter = BeliefFitter(planning, obj, cfg.sysid.mass_bounds_kg, cfg.sysid.friction_bounds)
        self._note(planning, obj)
        try:
            return self._attempts(robot, log, planning, fitter, obj)
        finally:
            log.figures(self.figures())

    def _attempts(self, robot: Any, log: TrialLog, planning: Any, fitter: Any, obj: str) -> bool:
        from kintsugi.methods.mppi.execute import run_attempt

        cfg = self.ctx.cfg
        for attempt in range(cfg.sysid.max_attempts):
            if attempt:
                robot.restart()
                log.event(robot.sim_time, "restart", f"attempt {attempt + 1} of {cfg.sysid.max_attempts}")
            robot.new_log()
            result, _ = run_attempt(cfg, robot, planning, self.design(self._design_ctx), log,
                                    seed=self._seed + 1000 * attempt)
            if result.reached:
                return True
            if attempt + 1 == cfg.sysid.max_attempts:
                break
            added = fitter.add(robot.new_log())
            phys, fit = fitter.fit()
            self._note(planning, obj)
            log.event(robot.sim_time, "sysid", fitter.story(added, phys, fit))
        return False

    def _note(self, planning: Any, obj: str) -> None:
        p = planning.physics_of(obj)
        self.history.append({"mass_kg": round(p.mass_kg, 5), "friction": round(p.friction, 5)})

    def figures(self) -> "SysIdFigures":
        return SysIdFigures(beliefs=self.history)


class SysIdFigures(Figures):
    """mppi-sysid's own figures: the beliefs after the prior and after each fit."""

    beliefs: list[dict[str, float]]


@METHODS.register("mppi-sysid", "system C: expert staged costs, planning world from a wrong prior (sysid.prior_*), "
                                "corrected by system identification after each failed attempt", tags=TAGS)
def make_mppi_sysid(ctx: Any, settings: object = None) -> MPPISysId:
    _check(ctx, "mppi-sysid")
    return MPPISysId(ctx)
