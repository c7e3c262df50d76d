"""The goal check judges the scene at rest: when the goal's own sub-goal names no open hand (a re-planned graph
that ends with a place), any open hand waits for the goal's objects to come to rest before the check reads them.
Otherwise a bottle just set down by a re-plan's stand-up is read while it still rocks, and a success is reported
that the scorer (which wants it at rest) does not count."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from kintsugi.methods.agentchord.conductor import Conductor


class Log:
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def event(self, t: float, kind: str, detail: str) -> None:
        self.events.append((kind, detail))


def _conductor(goal_gripper: dict, closed: dict) -> tuple[Conductor, list]:
    c = Conductor.__new__(Conductor)
    goal = SimpleNamespace(id="g", gripper=goal_gripper, constraints=())
    edge = SimpleNamespace(target="g", kind="nominal")
    c.graph = SimpleNamespace(goal="g", node=lambda _: goal, edges=[edge])
    c.goal_objects = {"bottle"}
    c.log, c._rested, c.pours, c.handover_goals = Log(), None, {}, frozenset()
    c.robot = SimpleNamespace(sim_time=1.0, control_steps=0, arm_state=lambda a: SimpleNamespace(gripper_closed=closed[a]))
    waits: list = []
    c.wait_still = lambda arm, names, e: waits.append((arm, set(names))) or True
    c._read = lambda names: SimpleNamespace(objects={}, arms={})
    return c, waits


@pytest.mark.parametrize(("gripper", "closed", "arm"), [
    ({"left": "open"}, {"left": False, "right": False}, "left"),   # the goal names its open hand
    ({}, {"left": True, "right": False}, "right"),                 # it names none: the hand that is open
])
def test_the_goal_check_waits_for_rest_with_an_open_hand(gripper: dict, closed: dict, arm: str) -> None:
    c, waits = _conductor(gripper, closed)
    assert c.goal_holds()
    assert waits == [(arm, {"bottle"})]


def test_with_every_hand_closed_nothing_is_opened_to_wait() -> None:
    c, waits = _conductor({}, {"left": True, "right": True})
    assert c.goal_holds() and waits == []
