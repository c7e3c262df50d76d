"""The paper's baseline: default goals CF0 -> CF4, no checks, no recovery."""

from __future__ import annotations

from kintsugi.methods import METHODS
from kintsugi.methods.skill_log import log_skill
from kintsugi.tasks.peg.context import PegContext
from kintsugi.tasks.peg.robot import PegRobot
from kintsugi.tasks.peg.skills import SEQUENCE
from kintsugi.trial import TrialLog


class Baseline:
    def __init__(self, ctx: PegContext) -> None:
        self.goals = ctx.full_goals()

    def run(self, robot: PegRobot, log: TrialLog) -> bool:
        """Framework verdict: every skill reported reaching its goal."""
        all_reached = True
        for skill in SEQUENCE:
            log.status(f"CF{SEQUENCE.index(skill)} {skill}")
            result = robot.execute(skill, self.goals[skill])
            log_skill(log, result, robot.sim_time)
            all_reached &= result.reached
        return all_reached


@METHODS.register("baseline", "default goals CF0->CF4, no checks, no recovery (paper: w/o recovery)",
                  tags=("peg-insertion",))
def make_baseline(ctx: PegContext) -> Baseline:
    return Baseline(ctx)
