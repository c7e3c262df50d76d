"""Turning a skill result into the trial log entry and a console line."""

from __future__ import annotations

from kintsugi.tasks.peg.robot import to_pose
from kintsugi.tasks.peg.skills import SKILLS, SkillResult
from kintsugi.trial import SkillLog, TrialLog


def log_skill(log: TrialLog, r: SkillResult, t: float, recovery: bool = False,
              verdict: bool | None = None, message: str = "") -> SkillLog:
    goal = to_pose(r.goal).model_dump()
    entry = SkillLog(
        skill=r.skill, goal={a: goal[a] for a in SKILLS[r.skill].axes},
        terminal=to_pose(r.terminal).model_dump(), reached=r.reached, timed_out=r.timed_out,
        compression_limit=r.compression_limit, recovery=recovery, verdict=verdict, message=message,
        sim_time=round(r.sim_time, 4),
    )
    log.skill(entry)
    flags = "reached" if r.reached else ("COMPRESSION LIMIT" if r.compression_limit else "timeout")
    goal_txt = ", ".join(f"{a}={v:.1f}" for a, v in entry.goal.items())
    log.say(f"[dim]{t:6.2f}s[/dim] CF{SKILLS[r.skill].cf} [bold]{r.skill}[/bold]{' (recovery)' if recovery else ''}"
            f" goal {goal_txt} -> {flags}, wrist {r.compression * 1000:.1f} mm", markup=True)
    return entry
