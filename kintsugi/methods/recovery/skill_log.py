"""Turning a skill result into the trial log entry and a console line, and a peg trial's own figures."""

from __future__ import annotations

from kintsugi.worlds.peg.robot import to_pose
from kintsugi.worlds.peg.skills import SKILLS, SkillResult
from kintsugi.core.log import TrialLog
from kintsugi.core.record import Figures, SkillLog

RECOVERY_SKILLS = ("fit", "align", "insert")
"""The contact formations a recovery plan may run again (Table II's columns)."""


class PegFigures(Figures):
    """A peg trial's own figures: executions beyond the first of each recoverable skill (Table II)."""

    extra_executions: dict[str, int]


def peg_figures(log: TrialLog) -> PegFigures:
    return PegFigures(extra_executions={s: max(0, log.executions.get(s, 0) - 1) for s in RECOVERY_SKILLS})


def log_skill(log: TrialLog, r: SkillResult, t: float, recovery: bool = False,
              verdict: bool | None = None, message: str = "") -> SkillLog:
    """Log `r` as ended at `t`, the robot's sim time after the skill (SkillLog.sim_time is absolute)."""
    goal = to_pose(r.goal).model_dump()
    entry = SkillLog(
        skill=r.skill, goal={a: goal[a] for a in SKILLS[r.skill].axes},
        terminal=to_pose(r.terminal).model_dump(), reached=r.reached, timed_out=r.timed_out,
        compression_limit=r.compression_limit, recovery=recovery, verdict=verdict, message=message,
        sim_time=round(t, 4),
    )
    log.skill(entry)
    flags = "reached" if r.reached else ("COMPRESSION LIMIT" if r.compression_limit else "timeout")
    goal_txt = ", ".join(f"{a}={v:.1f}" for a, v in entry.goal.items())
    log.say(f"[dim]{t:6.2f}s[/dim] CF{SKILLS[r.skill].cf} [bold]{r.skill}[/bold]{' (recovery)' if recovery else ''}"
            f" goal {goal_txt} -> {flags}, wrist {r.compression * 1000:.1f} mm", markup=True)
    return entry
