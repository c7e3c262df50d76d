"""Scripted reference executor for the tabletop tasks (system B): the task's fixed nominal
sequence of atomic actions, computed once from the first observation; no checks, no recovery.

Its framework verdict is "every action reached its target". It proves the world and the
actions before any reasoning is layered on top.
"""

from __future__ import annotations

from typing import Any

from rich.markup import escape

from kintsugi.core.errors import ConfigError
from kintsugi.core.registry import METHODS
from kintsugi.core.record import SkillLog
from kintsugi.core.log import TrialLog


def _numbers(action: dict[str, Any]) -> dict[str, float]:
    out: dict[str, float] = {}
    for k, v in action.items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            out[k] = round(float(v), 4)
        elif isinstance(v, (list, tuple)) and all(isinstance(x, (int, float)) for x in v):
            out |= {f"{k}{i}": round(float(x), 4) for i, x in enumerate(v)}
    return out


def describe(action: dict[str, Any]) -> str:
    args = ", ".join(f"{k}={v}" for k, v in action.items() if k != "action")
    return f"{action.get('action')}({args})"


class Scripted:
    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx

    def run(self, robot: Any, log: TrialLog) -> bool:
        first = robot.observation(images=False)
        all_reached = True
        from kintsugi.worlds.tabletop.task import expand

        actions = (a for entry in self.ctx.task.script(first) for a in expand(entry, robot))
        for action in actions:
            log.status(describe(action))
            result = robot.execute(action)
            arm = result.arms[0] if result.arms else "right"
            tcp = robot.arm_state(arm).tcp_pos
            log.skill(SkillLog(skill=result.action, goal=_numbers(action),
                               terminal={a: round(v * 1000, 2) for a, v in zip("xyz", tcp)},
                               reached=result.reached, message=result.message, sim_time=round(robot.sim_time, 4)))
            flag = "reached" if result.reached else ("IK FAILED" if result.ik_failed else "not reached")
            args = escape(describe(action)[len(result.action):])
            log.say(f"[dim]{robot.sim_time:6.2f}s[/dim] [bold]{result.action}[/bold]{args} -> {flag} "
                    f"({escape(result.message)})", markup=True)
            all_reached &= result.reached
        return all_reached


@METHODS.register("scripted", "fixed nominal atomic-action sequence per task, no checks, no recovery",
                  tags=("system-b",))
def make_scripted(ctx: Any, settings: object = None) -> Scripted:
    from kintsugi.worlds.tabletop.context import TabletopContext

    if not isinstance(ctx, TabletopContext):
        raise ConfigError("method 'scripted' runs the tabletop tasks (system B) only; "
                          "for peg-insertion use baseline or recovery")
    return Scripted(ctx)
