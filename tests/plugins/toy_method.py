"""A toy tabletop method in one file: the task's scripted sequence, stopped after `max_actions` actions.

Its typed settings take `--set method.max_actions=3` (an unknown key or a bad value is a one-line
error before any trial), and it writes its own figures into the record's `method_figures`.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.core.log import TrialLog
from kintsugi.core.record import Figures, SkillLog
from kintsugi.core.registry import METHODS
from kintsugi.methods.scripted import describe
from kintsugi.worlds.tabletop.task import expand


class FirstActionsSettings(StrictModel):
    max_actions: int = Field(1, ge=1)
    """Actions of the script to run before stopping."""


class FirstActionsFigures(Figures):
    ran: int
    reached: int
    stopped_early: bool


class FirstActions:
    def __init__(self, ctx: Any, settings: FirstActionsSettings) -> None:
        self.ctx, self.max_actions = ctx, settings.max_actions

    def run(self, robot: Any, log: TrialLog) -> bool:
        first = robot.observation(images=False)
        actions = (a for entry in self.ctx.task.script(first) for a in expand(entry, robot))
        ran = reached = 0
        stopped = False
        for action in actions:
            if ran == self.max_actions:
                stopped = True  # the script goes on: this method's verdict cannot be success
                break
            result = robot.execute(action)
            ran, reached = ran + 1, reached + result.reached
            log.skill(SkillLog(skill=result.action, goal={}, terminal={}, reached=result.reached,
                               message=result.message, sim_time=round(robot.sim_time, 4)))
            log.say(f"{robot.sim_time:6.2f}s {describe(action)} -> {'reached' if result.reached else 'missed'}")
        log.figures(FirstActionsFigures(ran=ran, reached=reached, stopped_early=stopped))
        return reached == ran and not stopped


METHODS.register("toy-first-actions", "toy plugin: a tabletop task's script, stopped after method.max_actions",
                 tags=("system-b",), config=FirstActionsSettings)(FirstActions)
