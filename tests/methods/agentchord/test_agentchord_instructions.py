"""The embedded composer reads who-holds-what from the instruction: "the cup with the left arm" binds the
cup to that arm (and "pour from the bottle ... using the right arm" the bottle), "hold the cup up" makes the cup lifted before anything is carried over or poured into it
(pour-dual), and an instruction that says neither plans as before."""

from __future__ import annotations

from kintsugi.methods.agentchord.composer import arm_bindings, embedded_compose, held_up
from tests.taskgraph_fixtures import POUR_GOAL, composer_request

DUAL = ("Pick up the cup with the left arm and the bottle with the right arm, hold the cup up, pour water "
        "from the bottle into it, then put both back upright on the table.")
DUAL_GOAL = POUR_GOAL + ["on_table(cup)", "released(cup)"]


def test_bindings_and_held_up_are_read_from_the_text() -> None:
    assert arm_bindings(DUAL, ["left", "right"], ["bottle", "cup"]) == {"cup": "left", "bottle": "right"}
    assert held_up(DUAL, ["bottle", "cup"]) == ["cup"]
    plain = "Pour water from the bottle into the cup using the right arm."
    assert arm_bindings(plain, ["left", "right"], ["bottle", "cup"]) == {"bottle": "right"}
    assert held_up(plain, ["bottle", "cup"]) == []
    assert arm_bindings("Pour water from the bottle into the cup.", ["left", "right"], ["bottle", "cup"]) == {}


def test_dual_pour_lifts_the_cup_with_the_left_arm_before_the_right_pours() -> None:
    ops = list(embedded_compose(composer_request(task=DUAL, goal=DUAL_GOAL)).edge_operators.values())
    assert "grasp(left, cup)" in ops and "grasp(right, bottle)" in ops
    assert not any(o.startswith(("grasp(left, bottle", "grasp(right, cup")) for o in ops)
    pour = ops.index("pour(right, bottle, cup)")
    assert ops.index("lift(left, cup)") < ops.index("carry_over(right, bottle, cup)") < pour
    assert ops.index("place(left, cup)") > pour


def test_without_held_up_the_cup_stays_on_the_table() -> None:
    text = "Pour water from the bottle with the right arm into the cup, then put the bottle back upright."
    ops = list(embedded_compose(composer_request(task=text)).edge_operators.values())
    assert ops[0] == "grasp(right, bottle)" and not any("cup)" in o and o.startswith(("grasp", "lift")) for o in ops)


def test_an_object_given_to_both_arms_is_never_taken_by_one() -> None:
    from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
    from kintsugi.methods.agentchord.instruction import instructed_ops

    def takes(text: str) -> set[str]:
        ops = instructed_ops(text, TABLETOP_DOMAIN, ["left", "right"], ["bottle", "cup"])
        return {o.label for o in ops if any(a[0] == "holding" and a[2] == "bottle" for a in o.add)
                and ("released", "bottle") in o.pre_pos}

    one = {"grasp(left, bottle)", "grasp(right, bottle)"}
    assert one <= takes("Put the bottle on the table.")
    assert not one & takes("Take the bottle with both arms and put it back.")
