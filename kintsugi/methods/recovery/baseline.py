"""The paper's baseline: default goals CF0 -> CF4, no checks, no recovery."""

from __future__ import annotations

from kintsugi.core.registry import METHODS
from kintsugi.methods.recovery.skill_log import log_skill, peg_figures
from kintsugi.worlds.peg.context import PegContext
from kintsugi.worlds.peg.robot import PegRobot
from kintsugi.worlds.peg.skills import SEQUENCE
from kintsugi.core.log import TrialLog


class Baseline:
    def __init__(self, ctx: PegContext) -> None:
        self.goals = ctx.full_goals()

    def run(self, robot: PegRobot, log: TrialLog) -> bool:
        """Framework verdict: every skill reported reaching its goal."""
        all_reached = True
        try:
            for skill in SEQUENCE:
                log.status(f"CF{SEQUENCE.index(skill)} {skill}")
                result = robot.execute(skill, self.goals[skill])
                log_skill(log, result, robot.sim_time)
                all_reached &= result.reached
        finally:
            log.figures(peg_figures(log))
        return all_reached


@METHODS.register("baseline", "default goals CF0->CF4, no checks, no recovery (paper: w/o recovery)",
                  tags=("peg-insertion",))
def make_baseline(ctx: PegContext, settings: object = None) -> Baseline:
    return Baseline(ctx)
