"""The goal relations a user's task needs (on, beside, left_of, right_of, inside, held_up), read off the
perceived scene as starting facts like every predicate with checks; the arm chosen by reach and cost; goals
that no plan can reach pruned before the search."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN as D
from kintsugi.methods.agentchord.facts import checked_facts, observed_facts
from kintsugi.methods.agentchord.symbolic import PlanningError, ground, parse_literals, plan, plan_each
from kintsugi.methods.agentchord.types import SeenArm, SeenObject

ARMS = [SeenArm(name="left", tcp_pos=(0.2, 0.3, 0.35), gripper_opening_m=0.1, gripper_closed=False),
        SeenArm(name="right", tcp_pos=(0.2, -0.3, 0.35), gripper_opening_m=0.1, gripper_closed=False)]


def box(name: str, c: tuple[float, float, float], half: float) -> SeenObject:
    x, y, z = c
    return SeenObject(name=name, visible=True, centroid=c, top_z=z + half, bottom_z=z - half,
                      extent=(2 * half,) * 3, extremes={"top": (x, y, z + half), "bottom": (x, y, z - half)},
                      n_points=500, upright=None)


def scene(*objects: SeenObject) -> SimpleNamespace:
    return SimpleNamespace(objects=list(objects), arms=ARMS, regions={})


def test_relations_are_read_from_the_perceived_scene() -> None:
    blue, red = box("blue", (0.44, 0.0, 0.025), 0.025), box("red", (0.44, 0.003, 0.072), 0.022)
    green = box("green", (0.44, 0.15, 0.022), 0.022)
    facts = checked_facts(scene(blue, red, green), D)
    assert ("on", "red", "blue") in facts and ("on", "blue", "red") not in facts
    assert ("left_of", "green", "blue") in facts and ("right_of", "blue", "green") in facts
    assert ("beside", "green", "blue") in facts and ("beside", "red", "green") not in facts  # red is not on the table
    assert not any(a[0] == "inside" for a in facts)  # stacked is not inside


def test_a_block_resting_on_a_bins_rim_is_not_inside_it() -> None:
    bin_ = SeenObject(name="bin", visible=True, centroid=(0.45, 0.0, 0.03), top_z=0.06, bottom_z=0.0,
                      extent=(0.2, 0.2, 0.06), extremes={"top": (0.45, 0.0, 0.06), "bottom": (0.45, 0.0, 0.0)},
                      n_points=900, upright=None)
    inside, on_rim = box("a", (0.45, 0.0, 0.027), 0.02), box("b", (0.45, 0.05, 0.082), 0.02)
    facts = checked_facts(scene(bin_, inside, on_rim), D)
    assert ("inside", "a", "bin") in facts and ("inside", "b", "bin") not in facts


def test_held_up_stands_for_lifted_and_held() -> None:
    assert parse_literals(["held_up(cup)"], D) == (frozenset({("lifted", "cup")}), frozenset({("released", "cup")}))
    with pytest.raises(PlanningError, match="not"):
        parse_literals(["not held_up(cup)"], D)


def _grasp_arm(objects: list[SeenObject], goal: list[str]) -> list[str]:
    request = scene(*objects)
    names = [o.name for o in objects]
    steps = plan(observed_facts(request, D), parse_literals(goal, D), ground(D, ["left", "right"], names))
    return [op.label for op in steps if op.name == "grasp"]


@pytest.mark.parametrize("y,arm", [(0.2, "left"), (-0.2, "right")])
def test_the_arm_is_chosen_by_reach_not_by_the_order_of_the_arms(y: float, arm: str) -> None:
    box_ = box("box", (0.47, 0.0, 0.04), 0.04)
    can = box("can", (0.35, y, 0.04), 0.02)
    side = "left_of" if y > 0 else "right_of"
    assert _grasp_arm([box_, can], [f"{side}(can, box)", "released(can)"]) == [f"grasp({arm}, can)"]


def test_an_object_out_of_both_arms_reach_is_a_planning_error() -> None:
    far = box("can", (1.3, 0.0, 0.02), 0.02)
    with pytest.raises(PlanningError, match="cannot be reached"):
        _grasp_arm([box("box", (0.47, 0.0, 0.04), 0.04), far], ["left_of(can, box)"])


def test_goals_no_plan_reaches_are_pruned_before_the_search() -> None:
    blue, red = box("blue", (0.44, 0.0, 0.025), 0.025), box("red", (0.40, 0.2, 0.022), 0.022)
    initial = observed_facts(scene(blue, red), D)
    ops = ground(D, ["left", "right"], ["blue", "red"])
    never = parse_literals(["on(red, blue)", "dropped(red)"], D)  # no action makes `dropped`
    # A budget of 5 states: a search would run out of it; the pruned goal is refused as unreachable at once.
    with pytest.raises(PlanningError, match="cannot be reached"):
        plan(initial, never, ops, max_expansions=5)
    found = plan_each(initial, [parse_literals(["on(red, blue)"], D), never], ops)
    assert found[0] and found[1] is None
