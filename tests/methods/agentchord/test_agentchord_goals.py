"""The embedded composer plans the region, handover and container goals of rearrange-table, handover-block and
coffee-tray from the goal text and perceived features (synthetic, no physics): the plan's operators, the filled
action arguments (region centres, the head turn), and the arranger's monitors for those edges."""

from __future__ import annotations

import pytest

from kintsugi.methods.agentchord.domain import BESIDE_M, TABLETOP_DOMAIN
from kintsugi.methods.agentchord.arranger import embedded_arrange
from kintsugi.methods.agentchord.composer import embedded_compose
from kintsugi.methods.agentchord.symbolic import PlanningError
from kintsugi.methods.agentchord.types import ArrangerRequest, ComposerRequest, SeenArm, SeenObject, parse_atom

ARMS = [SeenArm(name="left", tcp_pos=(0.3, 0.3, 0.3), gripper_opening_m=0.1, gripper_closed=False),
        SeenArm(name="right", tcp_pos=(0.3, -0.3, 0.3), gripper_opening_m=0.1, gripper_closed=False)]


def _lying(name: str, xy: tuple[float, float], head_dx: float, length: float = 0.18) -> SeenObject:
    """A utensil lying along x; its head (the end nearer the centroid) at +x when head_dx > 0."""
    x, y = xy
    return SeenObject(name=name, visible=True, centroid=(x, y, 0.006), top_z=0.012, bottom_z=0.0,
                      upright=False, extent=(length, 0.02, 0.012),
                      extremes={"axis_pos": (x + head_dx * 0.06, y, 0.006), "axis_neg": (x - head_dx * 0.12, y, 0.006)})


def _box(name: str, xy: tuple[float, float], size: tuple[float, float, float], upright: bool | None = None) -> SeenObject:
    x, y = xy
    return SeenObject(name=name, visible=True, centroid=(x, y, size[2] / 2), top_z=size[2], bottom_z=0.0,
                      upright=upright, extent=size)


COFFEE = ("Put the capsule upright into the tray with the left arm, then take the tray by its side rims with both "
          "arms and set it down in the region in front.")


def _compose(task: str, goal: list[str], objects: list[SeenObject], regions: dict | None = None):
    return embedded_compose(ComposerRequest(task=task, goal=goal, objects=objects, arms=ARMS,
                                            domain=TABLETOP_DOMAIN, regions=regions or {}))


def _ops(reply) -> list[str]:
    return [reply.edge_operators[e["id"]] for e in reply.graph["edges"]]


def test_place_terms_parse_as_one_constant() -> None:
    assert parse_atom("in_region(fork, beside_left(plate))") == (True, "in_region", ("fork", "beside_left(plate)"))
    with pytest.raises(ValueError, match="not a literal"):
        parse_atom("in_region(fork, beside(left(plate)))")


def test_rearrange_goal_plans_carry_turn_place_per_utensil() -> None:
    plate = _box("plate", (0.5, 0.0), (0.2, 0.2, 0.016), upright=True)
    fork = _lying("fork", (0.4, 0.25), head_dx=-1.0)  # head towards the robot: must turn 180 deg
    spoon = _lying("spoon", (0.4, -0.25), head_dx=1.0)  # already heading away
    goal = ["in_region(fork, beside_left(plate))", "in_region(spoon, beside_right(plate))", "flat(fork)",
            "flat(spoon)", "heading(fork, away)", "heading(spoon, away)", "released(fork)", "released(spoon)"]
    said = ("Place the fork to the left of the plate and the spoon to the right of it, each lying flat along the "
            "plate's side with its head pointing away from you. Use the left arm for the fork and the right arm "
            "for the spoon.")
    reply = _compose(said, goal, [plate, fork, spoon])
    ops = _ops(reply)
    assert "turn_heading(left, fork, away, beside_left(plate))" in ops
    assert not any(o.startswith("turn_heading(right, spoon") for o in ops)  # its head already points away
    assert "place_at(left, fork, beside_left(plate))" in ops and "place_at(right, spoon, beside_right(plate))" in ops
    acts = {e["description"]: e["actions"] for e in reply.graph["edges"]}
    place = acts["place_at(left, fork, beside_left(plate))"][0]["args"]
    assert place["x"] == pytest.approx(0.5) and place["y"] == pytest.approx(BESIDE_M)
    turn = acts["turn_heading(left, fork, away, beside_left(plate))"][0]["args"]["angle_deg"]
    assert abs(abs(turn) - 180.0) < 1e-6
    # The turn comes after the carry over the region (the wrist runs out of range near the shoulder).
    assert ops.index("carry_to(left, fork, beside_left(plate))") < ops.index("turn_heading(left, fork, away, "
                                                                             "beside_left(plate))")


def test_handover_goal_plans_take_then_let_go_and_place_in_the_named_region() -> None:
    block = _box("block", (0.4, 0.2), (0.05, 0.05, 0.05), upright=True)
    goal = ["handed_over(block, left, right)", "not dropped(block)", "in_region(block, target)", "flat(block)",
            "released(block)"]
    said = "Pick up the block with the left arm, hand it over to the right arm, and place it in the target region."
    reply = _compose(said, goal, [block], {"target": (0.40, -0.25)})
    assert _ops(reply) == ["grasp(left, block)", "lift(left, block)", "take_over(right, left, block)",
                           "let_go(left, right, block)", "carry_to(right, block, target)", "place_at(right, block, target)"]
    req = ArrangerRequest(task=said, graph=reply.graph, node_facts=reply.node_facts,
                          edge_operators=reply.edge_operators, objects=[block], arms=ARMS, domain=TABLETOP_DOMAIN,
                          regions={"target": (0.40, -0.25)})
    watched = {(p["edge"], p["monitor"]["failure_mode"], p["monitor"]["check"].get("arm"))
               for p in embedded_arrange(req).proposals}
    assert ("e3_take_over", "drop", "left") in watched  # the giver still holds it while the taker comes in
    assert not any(e == "e4_let_go" and m == "drop" and a == "left" for e, m, a in watched)  # lets go on purpose
    assert ("e5_carry_to", "drop", "right") in watched
    # After the handover the block is the right arm's: a drop there is picked up again by the right arm (the
    # left may not reach where it fell); before it, only the left takes it from the table.
    props = {(p["edge"], p["monitor"]["failure_mode"], p["monitor"]["check"].get("arm")): p
             for p in embedded_arrange(req).proposals}

    def takers(key: tuple) -> set[str]:
        return {a["args"]["arm"] for e in props[key]["edges"] for a in e["actions"] if a["name"] == "grasp"}
    assert takers(("e5_carry_to", "drop", "right")) == {"right"}
    assert takers(("e2_lift", "drop", "left")) == {"left"}


def test_unknown_region_is_a_planning_error_naming_it() -> None:
    block = _box("block", (0.4, 0.2), (0.05, 0.05, 0.05), upright=True)
    with pytest.raises(PlanningError, match="target region.*names no region"):
        _compose("Place the block in the target region.", ["in_region(block, target)"], [block])


def test_coffee_goal_puts_the_capsule_in_first_and_carries_the_wide_tray_with_both_arms() -> None:
    capsule = _box("capsule", (0.35, 0.25), (0.03, 0.03, 0.05), upright=True)
    tray = _box("tray", (0.40, 0.0), (0.22, 0.16, 0.04), upright=None)
    goal = ["inside(capsule, tray)", "upright(capsule)", "in_region(tray, tray_forward)", "flat(tray)",
            "released(capsule)", "released(tray)"]
    reply = _compose(COFFEE, goal, [capsule, tray], {"tray_forward": (0.56, 0.0)})
    assert _ops(reply) == ["grasp(left, capsule)", "lift(left, capsule)", "put_inside(left, capsule, tray)",
                           "take_both(tray)", "carry_both(tray, tray_forward)", "let_go_both(tray)"]
    edges = reply.graph["edges"]
    assert all(a["name"] == "drive" for e in edges[-3:] for a in e["actions"])
    move = edges[-2]["actions"][1]["args"]
    assert move["left"]["dxyz"][:2] == pytest.approx([0.16, 0.0]) == move["right"]["dxyz"][:2]
    carry = edges[-3]["actions"]
    rims = carry[0]["args"]
    assert rims["left"]["grasp_offset"][1] == pytest.approx(0.077) and rims["right"]["grasp_offset"][1] == pytest.approx(-0.077)


def test_two_arm_carry_is_watched_for_a_drop_and_recovers_by_taking_it_again_with_both() -> None:
    capsule = _box("capsule", (0.35, 0.25), (0.03, 0.03, 0.05), upright=True)
    tray = _box("tray", (0.40, 0.0), (0.22, 0.16, 0.04), upright=None)
    goal = ["inside(capsule, tray)", "upright(capsule)", "in_region(tray, tray_forward)", "flat(tray)",
            "released(capsule)", "released(tray)"]
    regions = {"tray_forward": (0.56, 0.0)}
    reply = _compose(COFFEE, goal, [capsule, tray], regions)
    req = ArrangerRequest(task=COFFEE, graph=reply.graph, node_facts=reply.node_facts,
                          edge_operators=reply.edge_operators, objects=[capsule, tray], arms=ARMS,
                          domain=TABLETOP_DOMAIN, regions=regions)
    props = embedded_arrange(req).proposals
    drops = [p for p in props if p["edge"] == "e5_carry_both" and p["monitor"]["failure_mode"] == "drop"]
    assert sorted(p["monitor"]["check"]["arm"] for p in drops) == ["left", "right"]
    assert not any(p["edge"] == "e6_let_go_both" for p in props)  # it opens on purpose
    assert not any(p["monitor"]["failure_mode"] in ("slip", "missed_grasp") and p["edge"] in ("e4_take_both",
                                                                                             "e5_carry_both")
                   for p in props)  # held by thin rims, far from the centroid
    edges = drops[0]["edges"]
    assert edges[0]["actions"] == [{"name": "open_gripper", "args": {"arm": "left"}}]  # the hub: let it come to rest
    fell = [e for e in edges if ".fell." in e["id"]]
    assert fell[0]["actions"][0]["name"] == "drive" and fell[0]["actions"][0]["args"]["left"]["action"] == "grasp"
    assert fell[-1]["target"] == "s5_carry_both" and not fell[0]["guard"]
    # Or it landed in its region: released into a later node, guarded by that node's facts about the tray. Both
    # hands open: it fell from both, and a merge node that counts both empty must not leave the right one closed
    # on it (coffee-tray seed 0 was called a success with the right hand still holding the tray).
    (landed,) = [e for e in edges if ".landed." in e["id"]]
    assert landed["actions"] == [{"name": "open_gripper", "args": {"arm": a}} for a in ("left", "right")]
    assert landed["target"] not in ("s4_take_both", "s5_carry_both") and landed["target"].startswith("s")
    assert {"in_region"} <= {c["kind"] for c in landed["guard"]}
    # The capsule going `inside` the tray: its guard checks that (over the tray's footprint, below its rim), not
    # only its other facts, which hold where it started too.
    capsule_drops = [p for p in props if p["monitor"]["check"].get("object") == "capsule"]
    guards = [e["guard"] for p in capsule_drops for e in p["edges"] if ".landed." in e["id"]]
    assert guards and all({"within", "above"} <= {c["kind"] for c in g if "tray" in str(c)} for g in guards)
    # The two-arm hold node checks the pads, not the centroid's distance from each hand.
    taken = next(n for p in drops for n in p["nodes"] if n.get("constraints"))
    assert {c["kind"] for c in taken["constraints"]} == {"touching"}


@pytest.mark.parametrize("forbid", [False, True])
def test_a_fall_into_place_is_a_branch_only_when_the_goal_allows_a_drop(forbid: bool) -> None:
    """A drop while carrying or placing the block may land it in its region: with a guard made of the place's
    own facts about it, the branch releases into the place's target. `not dropped(block)` (the instruction asks
    for it to be set down) leaves that branch out: a fall is never a place."""
    block = _box("block", (0.40, 0.20), (0.05, 0.05, 0.05))
    goal = ["in_region(block, target)", "flat(block)", "released(block)"] + (["not dropped(block)"] if forbid else [])
    regions = {"target": (0.40, -0.25)}
    reply = _compose("Place the block in the target region.", goal, [block], regions)
    req = ArrangerRequest(task="Place the block in the target region.", graph=reply.graph, node_facts=reply.node_facts, goal=goal,
                          edge_operators=reply.edge_operators, objects=[block], arms=ARMS, domain=TABLETOP_DOMAIN,
                          regions=regions)
    drops = [p for p in embedded_arrange(req).proposals if p["monitor"]["failure_mode"] == "drop"]
    landed = [e for p in drops for e in p["edges"] if ".landed." in e["id"]]
    assert drops and bool(landed) is not forbid
    for e in landed:
        assert {c["kind"] for c in e["guard"]} >= {"in_region", "above"}  # in the region, lying flat
        assert [a["name"] for a in e["actions"]] == ["open_gripper"]
