"""An object the instruction gives to one arm that lies where that arm cannot reach it (knocked or dropped
across the table) is taken up by the arm that can (the plan may then pass the other object over, as handovers
always could); where the instruction's arm reaches it, only that arm takes it up."""

from __future__ import annotations

from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.instruction import instructed_ops
from kintsugi.methods.agentchord.symbolic import parse_literals, plan

DUAL = ("Pick up the cup with the left arm and the bottle with the right arm, hold the cup up, pour water from the "
        "bottle into it, then put both back upright on the table.")
GOAL = ["on_table(cup)", "upright(cup)", "released(cup)", "on_table(bottle)", "upright(bottle)", "released(bottle)",
        "poured(bottle, cup)"]


def _facts(cup_reached_by: tuple[str, ...]) -> frozenset:
    """Both on the table and released, both hands empty; the bottle upright; the cup lying flat."""
    facts = {("hand_empty", "left"), ("hand_empty", "right"), ("narrow", "cup"), ("narrow", "bottle"),
             ("on_table", "cup"), ("on_table", "bottle"), ("released", "cup"), ("released", "bottle"),
             ("stands", "cup"), ("stands", "bottle"), ("upright", "bottle"), ("flat", "cup"),
             ("reaches", "left", "bottle"), ("reaches", "right", "bottle"), ("nearer", "right", "bottle")}
    facts |= {("reaches", a, "cup") for a in cup_reached_by}
    facts.add(("nearer", cup_reached_by[0], "cup"))
    return frozenset(facts)


def _plan(cup_reached_by: tuple[str, ...]) -> list[str]:
    ops = instructed_ops(DUAL, TABLETOP_DOMAIN, ["left", "right"], ["bottle", "cup"])
    return [op.label for op in plan(_facts(cup_reached_by), parse_literals(GOAL, TABLETOP_DOMAIN), ops)]


def test_the_instructions_arm_takes_what_it_reaches() -> None:
    steps = _plan(("left", "right"))
    assert any(s.startswith(("stand_up(left, cup)", "grasp_lying(left, cup)")) for s in steps)
    assert not any(s.endswith("(right, cup)") for s in steps)


def test_the_other_arm_takes_up_what_the_instructions_arm_cannot_reach() -> None:
    steps = _plan(("right",))
    assert any(s.startswith(("stand_up(right, cup)", "grasp_lying(right, cup)")) for s in steps)
    assert any(s.startswith("pour(") for s in steps)
