"""A re-plan that finds the goal already holding is an answer: its transcript record is no reasoner error."""

from __future__ import annotations

from kintsugi.methods.agentchord.composer import GoalHolds, record_goal_holds
from kintsugi.reasoning.base import CallRecord


def _rec(error: str | None) -> CallRecord:
    return CallRecord(role="composer", backend="embedded", request={}, reply=None, error=error)


def test_the_finding_becomes_the_reply() -> None:
    records = [_rec(None), _rec(f"GoalHolds: {GoalHolds('the goal already holds in the observed scene')}")]
    record_goal_holds(records)
    assert records[-1].error is None
    assert records[-1].reply == {"goal_holds": "the goal already holds in the observed scene"}


def test_other_errors_stay_errors() -> None:
    records = [_rec("PlanningError: no plan reaches the goal")]
    record_goal_holds(records)
    assert records[-1].error == "PlanningError: no plan reaches the goal"
    record_goal_holds([])  # nothing recorded: nothing to do
