"""System C's baseline methods: hand-written expert costs on MPPI, with and without a true world model.

- `expert`: one hand-written cost per task; planning world = the truth (oracle physics).
- `expert-fsm`: hand-written staged costs with transitions; planning world = the truth
  (the paper's upper bound).
- `mppi-sysid`: the expert-FSM costs, but the planning world starts from a wrong prior
  (nominal masses x `sysid.prior_mass_scale`, frictions x `sysid.prior_friction_scale`)
  and system identification corrects it from the logged attempt after each failure.
"""

from __future__ import annotations

from typing import Any

from kintsugi.errors import ConfigError
from kintsugi.methods import METHODS
from kintsugi.trial import TrialLog

TAGS = ("system-c",)
ORACLE = ("system-c", "oracle-physics")


def _check(ctx: Any, name: str) -> None:
    from kintsugi.tasks.contact.context import ContactContext

    if not isinstance(ctx, ContactContext):
        raise ConfigError(f"method {name!r} runs the contact tasks (system C) only")


class Expert:
    """One attempt of a hand-written cost, planning in a world that holds the true physics."""

    def __init__(self, ctx: Any, staged: bool) -> None:
        from kintsugi.tasks.contact.experts import expert_design

        if ctx.oracle_physics is None:
            raise ConfigError("the expert baselines plan in the true world: register them with the "
                              "'oracle-physics' tag")
        self.ctx = ctx
        self.design = expert_design(ctx.task.name, staged)

    def run(self, robot: Any, log: TrialLog) -> bool:
        from kintsugi.tasks.contact.execute import run_attempt
        from kintsugi.tasks.contact.world import PlanningWorld

        planning = PlanningWorld(self.ctx.cfg, self.ctx.known, self.ctx.oracle_physics)
        result, _ = run_attempt(self.ctx.cfg, robot, planning, self.design(self.ctx), log, seed=self.ctx.seed)
        return result.reached


@METHODS.register("expert", "system C: hand-written single-stage MPPI cost per task, planning world = truth",
                  tags=ORACLE)
def make_expert(ctx: Any) -> Expert:
    _check(ctx, "expert")
    return Expert(ctx, staged=False)


@METHODS.register("expert-fsm", "system C: hand-written staged MPPI costs with transitions, planning world = truth "
                                "(the paper's upper bound)", tags=ORACLE)
def make_expert_fsm(ctx: Any) -> Expert:
    _check(ctx, "expert-fsm")
    return Expert(ctx, staged=True)
