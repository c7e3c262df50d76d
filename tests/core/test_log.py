"""The trial log stamps what a method reports with the wall time since the trial started."""

from __future__ import annotations

import time

from kintsugi.core.log import TrialLog
from kintsugi.core.record import SkillLog, TrialRecord


def test_skills_and_events_carry_wall_time_and_without_timings_drops_it() -> None:
    log = TrialLog(started=time.perf_counter() - 2.0)  # the trial began two seconds ago
    log.event(0.5, "monitor", "drop")
    log.skill(SkillLog(skill="grasp", goal={}, terminal={}, reached=True, sim_time=1.0))
    assert all(2.0 <= x.wall_s < 60.0 for x in (log.events[0], log.skills[0]))
    r = TrialRecord(key="t/m/v/c/0", task="t", method="m", variant="v", condition="c", seed=0,
                    events=log.events, skills=log.skills)
    plain = r.without_timings()
    assert "wall_s" not in plain["events"][0] and "wall_s" not in plain["skills"][0]
    assert plain["events"][0]["kind"] == "monitor" and plain["skills"][0]["skill"] == "grasp"
