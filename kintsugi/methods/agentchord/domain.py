"""The tabletop atomic actions (paper Table IV) written as a planning domain: predicates with the
feature constraints that check them, operators with preconditions, effects, action templates and costs.

This is what the composer is told about the action library (a model reads it in the request, the
embedded planner searches it); it names no task. Costs are nominal control steps (10 ms each) at the
configured motion speeds, used for Eq. 8's cost-to-go.
"""

from __future__ import annotations

from kintsugi.methods.agentchord.types import Domain, OperatorSpec, PredicateSpec

LIFT_M = 0.12
POUR_SIDE_M = 0.10
"""While pouring, the grasp point sits this far beside the target, on the pouring arm's side."""
POUR_HEIGHT_M = 0.14
POUR_DEG = 100.0
SIDE_FORWARD_RPY = [0.0, 90.0, 0.0]
"""Gripper horizontal, pointing +x: carries an upright object side-on."""
BESIDE_M = 0.18
"""`beside_left(o)` / `beside_right(o)`: a region this far left / right (world y) of the object's centre."""
HANDOVER_XYZ = [0.42, 0.0, 0.20]
"""Where a giving arm presents a held object between the two arms (grasp point, gripper pointing down)."""
DOWN_RPY = [0.0, 180.0, 0.0]
TAKE_REACH_M = 0.10
"""The taking arm comes in side-on from this far beside the presented object, then closes in..."""
TAKE_DEPTH_M = 0.01
"""...stopping this short of its centre (its palm stays off the giver's fingers)..."""
TAKE_HIGH_M = 0.012
"""...and this far above it (its palm clears the table when it later places the object)."""
GIVER_CLEAR_M = 0.08
INSIDE_AT_M = -0.03
"""Objects go into a container this far behind its centre (x), clear of rims an arm may later take."""
INSIDE_FLOOR_M = 0.014
"""Placing into a shallow container: release this high above the table (its floor plus a clearance)."""
INSIDE_MARGIN_M = 0.01
"""`inside`: the object's centre this far within the container's outer footprint (clear of a rim's width)."""
INSIDE_BELOW_RIM_M = 0.008
INSIDE_FLOOR_SLACK_M = 0.005
"""`inside`: the object's bottom at least INSIDE_BELOW_RIM_M below the container's rim and no lower than its
bottom (less this slack): in it, not resting on its rim, and not under it."""
RIM_FORWARD_M = 0.05
RIM_HOLD_Z_M = 0.025
RIM_INSET_M = 0.003
"""Two-arm carry: each arm takes a side rim this far forward of the centre, this high, this far inside the
perceived side (half a wall)."""
CARRY_LIFT_M = 0.03
UPEND_LIFT_M = 0.15
"""Standing a fallen object up: lift it this high before turning it (its lower half swings down)."""
HEADING_TOL_DEG = 10.0
"""A sub-goal `heading` holds when the perceived head (judged with no hand on the object) is this close to it.
Tighter than any judge is likely to be (rearrange scores 15 degrees): perception reads a lying fork's head to a
few degrees, and a looser check passed a fork left 17 degrees off (rearrange seed 87, a false success)."""
GENTLE_CLOSE_S = 0.2
"""Closing on an object lying flat: the fingers are brought closed over this long rather than at once."""
FLAT_MARGIN_M = 0.008
"""`flat` holds while the object's height exceeds its thinnest perceived span by no more than this (perception
reads a lying fork's height to a few millimetres; one on its side is 2-3 cm taller)."""
REGION_TOL_M = 0.04
"""A sub-goal `in_region` of a region the task gives no size holds when the perceived centroid is this close (x
and y) to the region's centre; a stated size is checked less `RELATION_MARGIN_M` (never looser than the scorer)."""
ON_MARGIN_M = 0.005
"""`on(x, y)`: x's centre this far inside y's perceived footprint..."""
ON_GAP_M = (-0.01, 0.012)
"""...and x's bottom this far below / above y's top (perception reads both to a few millimetres)."""
RELATION_MARGIN_M = 0.005
"""Perception's error on one object's centre relative to another's, as the relation checks below read it:
at most 1.8 mm over 48 can-to-box offsets (flank-box under `pose`, standing cans at rest, the box turned up
to 15 degrees), rounded up."""
UNSTATED_REGION_HALF_M = REGION_TOL_M + RELATION_MARGIN_M
"""The half-extent of a region the task gives no size: checked within `REGION_TOL_M` of its centre."""
SIDE_M = (0.06 + RELATION_MARGIN_M, 0.28 - RELATION_MARGIN_M)
"""`left_of` / `right_of`: x's centre this far to the side (world y) of y's centre...

The tabletop scorers' bounds (6-28 cm to the side, within 8 cm front to back) shrunk by RELATION_MARGIN_M: a
relation the method reads as holding then holds on the true poses too (the verdict is never looser than the
scorer), while an object the scorer accepts is refused only within perception's error of a bound (any narrower
band fails trials the scorer counts as successes)."""
SIDE_ALONG_M = 0.08 - RELATION_MARGIN_M
"""...and within this of it front to back (world x)."""
SIDE_AIM_M = 0.15
"""Where a place beside an object aims: this far to its side (well inside SIDE_M)."""
BESIDE_M_RANGE = (0.06 + RELATION_MARGIN_M, 0.28 - RELATION_MARGIN_M)
"""`beside(x, y)`: the centres this far apart horizontally, either side: the scorers' `beside` bounds shrunk
by RELATION_MARGIN_M, as for SIDE_M (a place to one side also makes `beside`, which the goal check reads too)."""
ON_TABLE_MARGIN_M = 0.005
"""Perception's error on a resting object's lowest point (its perceived `bottom`, against the scorer's lowest
point of the true pose), over 384 readings of the declared tabletop tasks' objects at rest under `pose`, standing
and tipped onto a side: -0.5 to +3.2 mm for fitted primitives, up to +4.1 mm for a fork or spoon read from its
points (a spoon on its edge hides its lowest edge), rounded up. Not counted: a spoon or fork on its edge that the
scorer's bounding box puts 7 mm into the table, and one box fitted with the wrong face up (1 of 384), read 10 mm
low, more than the scorer's 1 cm leaves room for (the check fails that resting box)."""
ON_TABLE_M = (-(0.01 - ON_TABLE_MARGIN_M), 0.01 - ON_TABLE_MARGIN_M)
"""`on_table`: the object's perceived lowest point this far below / above the table top: the tabletop scorers'
bound (within 1 cm) shrunk by ON_TABLE_MARGIN_M, so an object the method reads as on the table is on it in the
true poses too (the verdict is never looser than the scorer). The planner's reading of a scene
(`facts.ON_TABLE_Z_M`, 3 cm) stays looser: it decides what may be taken up (an object resting on something low), not
whether the task is done."""
ARM_BASES = {"left": (-0.05, 0.30), "right": (-0.05, -0.30)}
"""The robot's description: where each arm's base stands (the default robot: bases 0.6 m apart at x = -0.05)."""
REACH_M = 0.72
"""How far from its base an arm takes an object on the table (upper arm and forearm 0.75 m, less a margin)."""
FAR_COST = 120.0
"""Extra cost of taking an object with the arm whose base is the farther from it (reaching across the body
is longer and nearer the arm's limits): the arm is chosen by reach and cost, not by the order of the arms."""
STACK_RISE_M = 0.05
"""After setting an object down on another, the hand rises this far before it goes home (it does not drag
the top object off)."""


def _p(name, params, meaning, constraints=(), gripper=None, static=False) -> PredicateSpec:  # noqa: ANN001
    return PredicateSpec(name=name, params=list(params), meaning=meaning, constraints=list(constraints),
                         gripper=gripper, static=static)


PREDICATES = [
    _p("hand_empty", ["arm"], "the arm's gripper is open and holds nothing", gripper="open"),
    _p("holding", ["arm", "object"], "the arm holds the object between its fingers",
       [{"kind": "detached", "arm": "?1", "object": "?2", "tol": 0.08},
        {"kind": "touching", "arm": "?1", "object": "?2"}], gripper="closed"),
    _p("on_table", ["object"], "the object rests on the table",
       [{"kind": "in_region", "point": {"entity": "?1", "feature": "bottom"},
         "lo": [-2.0, -2.0, ON_TABLE_M[0]], "hi": [2.0, 2.0, ON_TABLE_M[1]]}]),
    _p("lifted", ["object"], "the object is held clear of the table",
       [{"kind": "in_region", "point": {"entity": "?1", "feature": "bottom"},
         "lo": [-2.0, -2.0, 0.05], "hi": [2.0, 2.0, 2.0]}]),
    _p("upright", ["object"], "the object's axis is vertical", [{"kind": "upright", "object": "?1", "tol_deg": 15}]),
    _p("over", ["object", "object"], "the first object is held above the second, beside its axis",
       [{"kind": "misaligned", "a": {"entity": "?1"}, "b": {"entity": "?2"}, "tol": 0.15},
        {"kind": "above", "a": {"entity": "?1"}, "b": {"entity": "?2", "feature": "top"}, "min_gap": 0.02}]),
    _p("tilted", ["object"], "the object is tilted to pouring", [{"kind": "tilted", "object": "?1", "min_deg": 60}]),
    _p("poured", ["object", "object"], "the first object was tilted to pour over the second (history)"),
    _p("released", ["object"], "no arm holds the object"),
    _p("flat", ["object"], "the object lies flat (it is no taller than it is wide), on the table or level in the hand; "
       "checked as: its height (top above bottom) no more than its thinnest perceived span plus a margin (a fork "
       "or spoon rolled onto its side is as tall as its head is wide)",
       [{"kind": "above", "a": {"entity": "?1", "feature": "bottom", "offset": [0.0, 0.0, f"$thin(?1, {FLAT_MARGIN_M})"]},
         "b": {"entity": "?1", "feature": "top"}, "min_gap": 0.0}]),
    _p("stands", ["object"], "the object has a base it stands on: it was seen standing with a clear axis (a bottle, "
       "a cup; not a cube or a fork), so it can fall over and be stood back up (static)", static=True),
    _p("narrow", ["object"], "the object fits between one gripper's open fingers (static, from its perceived size)",
       static=True),
    _p("region", ["place"], "the place is a region of the table (static)", static=True),
    _p("direction", ["place"], "the place is a direction a heading goal may name (static)", static=True),
    _p("over_place", ["object", "place"], "the held object is carried above the region"),
    _p("in_region", ["object", "place"], "the object's centre lies in the region",
       [{"kind": "in_region", "point": {"entity": "?1", "feature": "centre"},
         "lo": [f"$rxlo(?2, {RELATION_MARGIN_M})", f"$rylo(?2, {RELATION_MARGIN_M})", -1.0],
         "hi": [f"$rxhi(?2, {RELATION_MARGIN_M})", f"$ryhi(?2, {RELATION_MARGIN_M})", 2.0]}]),
    _p("heading", ["object", "place"], "the lying object's head points in the direction",
       [{"kind": "heading", "object": "?1", "yaw_deg": "$yaw(?2)", "tol_deg": HEADING_TOL_DEG}]),
    _p("handed_over", ["object", "arm", "arm"], "the first arm held the object, then the second took it (history)"),
    _p("dropped", ["object"], "the object fell from a gripper (history; no action makes it)"),
    _p("inside", ["object", "object"], "the first object stands inside the second (a container): its centre within "
       "the container's footprint seen from above (its perceived length along its axis and width across it), "
       "clear of the rims, its bottom below the container's rim and above the container's bottom",
       [{"kind": "within", "point": {"entity": "?1"}, "container": "?2", "margin": INSIDE_MARGIN_M},
        {"kind": "above", "a": {"entity": "?2", "feature": "top"}, "b": {"entity": "?1", "feature": "bottom"},
         "min_gap": INSIDE_BELOW_RIM_M},
        {"kind": "above", "a": {"entity": "?1", "feature": "bottom"}, "b": {"entity": "?2", "feature": "bottom"},
         "min_gap": -INSIDE_FLOOR_SLACK_M}]),
    _p("moved", ["object"], "the object was carried away from where it was first seen"),
    _p("reaches", ["arm", "object"], "the object lies within the arm's reach (its perceived centre within the "
       "domain's reach_m of the arm's base)"),
    _p("nearer", ["arm", "object"], "no other arm's base is nearer to the object"),
    _p("on", ["object", "object"], "the first object rests on top of the second (stacked): its centre within the "
       "second's perceived footprint, its bottom at the second's top",
       [{"kind": "within", "point": {"entity": "?1"}, "container": "?2", "margin": ON_MARGIN_M},
        {"kind": "offset", "a": {"entity": "?1", "feature": "bottom"}, "b": {"entity": "?2", "feature": "top"},
         "lo": [-2.0, -2.0, ON_GAP_M[0]], "hi": [2.0, 2.0, ON_GAP_M[1]]}]),
    _p("beside", ["object", "object"], "the first object is next to the second on the table, either side: their "
       f"centres {BESIDE_M_RANGE[0]}-{BESIDE_M_RANGE[1]} m apart horizontally",
       [{"kind": "spacing", "a": {"entity": "?1"}, "b": {"entity": "?2"}, "min_m": BESIDE_M_RANGE[0],
         "max_m": BESIDE_M_RANGE[1]},
        {"kind": "in_region", "point": {"entity": "?1", "feature": "bottom"}, "lo": [-2.0, -2.0, ON_TABLE_M[0]],
         "hi": [2.0, 2.0, ON_TABLE_M[1]]}]),
    _p("left_of", ["object", "object"], "the first object is to the left (+y, the robot's left) of the second: "
       f"its centre {SIDE_M[0]}-{SIDE_M[1]} m to that side, within {SIDE_ALONG_M} m of it front to back",
       [{"kind": "offset", "a": {"entity": "?1"}, "b": {"entity": "?2"}, "lo": [-SIDE_ALONG_M, SIDE_M[0], -2.0],
         "hi": [SIDE_ALONG_M, SIDE_M[1], 2.0]}]),
    _p("right_of", ["object", "object"], "the first object is to the right (-y) of the second, as for left_of",
       [{"kind": "offset", "a": {"entity": "?1"}, "b": {"entity": "?2"}, "lo": [-SIDE_ALONG_M, -SIDE_M[1], -2.0],
         "hi": [SIDE_ALONG_M, -SIDE_M[0], 2.0]}]),
]


RELATIONS = [f"{r}({a}, {b})" for r in ("on", "beside", "left_of", "right_of", "inside", "in_region")
             for a, b in (("?obj", "_"), ("_", "?obj")) if not (r == "in_region" and a == "_")]
"""What lifting an object ends: its relations to others, and theirs to it (wild deletes)."""


def _op(name, params, pre, add, delete, actions, cost, description) -> OperatorSpec:  # noqa: ANN001
    return OperatorSpec(name=name, params=params, pre=pre, add=add, delete=delete, actions=actions, cost=cost,
                        description=description)


A, O, T = "?arm", "?obj", "?target"
G, P, D, C = "?giver", "?place", "?dir", "?box"


def _both(call: dict, per_arm: dict | None = None) -> dict:
    """One `drive` action: the same call on both arms at once, with per-arm extra arguments."""
    arms = {arm: {"action": call["name"], "arm": arm, **call["args"], **(per_arm or {}).get(arm, {})}
            for arm in ("left", "right")}
    return {"name": "drive", "args": arms}
OPERATORS = [
    _op("grasp", {A: "arm", O: "object"},
        ["hand_empty(?arm)", "narrow(?obj)", "upright(?obj)", "on_table(?obj)", "released(?obj)"],
        ["holding(?arm, ?obj)"], ["hand_empty(?arm)", "released(?obj)"],
        [{"name": "grasp", "args": {"arm": A, "obj": O, "pre_grasp_offset": 0.08}}], 260,
        "open, approach an upright object side-on from its pre-grasp pose, close on it"),
    _op("lift", {A: "arm", O: "object"}, ["holding(?arm, ?obj)", "on_table(?obj)"],
        ["lifted(?obj)"], ["on_table(?obj)", *RELATIONS],
        [{"name": "move_by_offset", "args": {"arm": A, "dxyz": [0.0, 0.0, LIFT_M]}}], 90,
        "raise the held object straight up"),
    _op("carry_over", {A: "arm", O: "object", T: "object"},
        ["holding(?arm, ?obj)", "lifted(?obj)", "upright(?obj)", "not over(?obj, ?target)"],
        ["over(?obj, ?target)"], [],
        [{"name": "move_to_obj", "args": {"arm": A, "obj": T, "offset": [0.0, f"$mirror(?arm, -{POUR_SIDE_M})",
                                                                          POUR_HEIGHT_M],
                                          "rpy_deg": SIDE_FORWARD_RPY}}], 140,
        "carry the held object upright to beside and above the target"),
    _op("pour", {A: "arm", O: "object", T: "object"},
        ["holding(?arm, ?obj)", "over(?obj, ?target)", "upright(?obj)"],
        ["tilted(?obj)", "poured(?obj, ?target)"], ["upright(?obj)"],
        [{"name": "rotate_eef", "args": {"arm": A, "angle_deg": f"$mirror(?arm, -{POUR_DEG})", "axis": "approach"}}],
        110, "tilt the held object about the gripper's approach axis so its mouth turns over the target"),
    _op("restore", {A: "arm", O: "object"}, ["holding(?arm, ?obj)", "tilted(?obj)"],
        ["upright(?obj)"], ["tilted(?obj)"],
        [{"name": "rotate_eef", "args": {"arm": A, "angle_deg": f"$mirror(?arm, {POUR_DEG})", "axis": "approach"}}],
        110, "turn the held object back upright"),
    _op("place", {A: "arm", O: "object"}, ["holding(?arm, ?obj)", "upright(?obj)", "lifted(?obj)"],
        ["on_table(?obj)", "released(?obj)", "hand_empty(?arm)"],
        ["holding(?arm, ?obj)", "lifted(?obj)", "over(?obj, _)"],
        [{"name": "place", "args": {"arm": A, "x": "$x(?obj)", "y": "$y(?obj)"}}], 260,
        "lower the held object onto the table where it was first seen, release it, back away"),
    _op("grasp_lying", {A: "arm", O: "object"},
        ["hand_empty(?arm)", "narrow(?obj)", "flat(?obj)", "not upright(?obj)", "on_table(?obj)",
         "released(?obj)"],
        ["holding(?arm, ?obj)"], ["hand_empty(?arm)", "released(?obj)"],
        [{"name": "grasp", "args": {"arm": A, "obj": O, "pre_grasp_offset": 0.06, "close_s": GENTLE_CLOSE_S}}], 280,
        "open, come down over an object lying flat, close on it gently (a thin utensil struck by both pads at "
        "once can pop up onto its side)"),
    _op("stand_up", {A: "arm", O: "object"},
        ["hand_empty(?arm)", "narrow(?obj)", "stands(?obj)", "not upright(?obj)", "on_table(?obj)",
         "released(?obj)"],
        ["upright(?obj)"], [],
        [{"name": "grasp", "args": {"arm": A, "obj": O, "pre_grasp_offset": 0.06}},
         {"name": "move_by_offset", "args": {"arm": A, "dxyz": [0.0, 0.0, UPEND_LIFT_M]}},
         {"name": "rotate_eef", "args": {"arm": A, "angle_deg": 90.0, "axis": "closing"}},
         {"name": "place", "args": {"arm": A, "x": "$x(?obj)", "y": "$y(?obj)"}}], 720,
        "stand a fallen object back up: grasp it lying (top-down, across its axis), lift it, turn the hand a "
        "quarter turn about the closing axis (the way that brings the object's top up), set it down upright "
        "where it was first seen and release it"),
    _op("carry_to", {A: "arm", O: "object", P: "place"},
        ["holding(?arm, ?obj)", "lifted(?obj)", "region(?place)", "not over_place(?obj, ?place)"],
        ["over_place(?obj, ?place)"], ["over_place(?obj, _)", "over(?obj, _)"],
        [{"name": "move_to_target", "args": {"arm": A, "xyz": [f"$rx({P})", f"$ry({P})", f"$z({O}, {LIFT_M})"]}}],
        140, "carry the held object, keeping the hand's orientation, to a lifted height above the region's centre "
        "(an absolute target, so it holds wherever the object was picked up)"),
    _op("turn_heading", {A: "arm", O: "object", D: "place", P: "place"},
        ["holding(?arm, ?obj)", "lifted(?obj)", "flat(?obj)", "direction(?dir)", "over_place(?obj, ?place)",
         "not heading(?obj, ?dir)"],
        ["heading(?obj, ?dir)"], ["heading(?obj, _)"],
        [{"name": "rotate_eef", "args": {"arm": A, "angle_deg": f"$turn({O}, {D})", "axis": "approach"}}], 110,
        "turn the held lying object about the vertical until its head points in the direction (over its "
        "region: near the shoulder the wrist runs out of range)"),
    _op("place_at", {A: "arm", O: "object", P: "place"},
        ["holding(?arm, ?obj)", "lifted(?obj)", "over_place(?obj, ?place)"],
        ["in_region(?obj, ?place)", "on_table(?obj)", "released(?obj)", "hand_empty(?arm)"],
        ["holding(?arm, ?obj)", "lifted(?obj)", "over(?obj, _)", "over_place(?obj, _)"],
        [{"name": "place", "args": {"arm": A, "x": f"$rx({P})", "y": f"$ry({P})"}},
         {"name": "back", "args": {"arm": A}}], 300,
        "lower the held object, carried above the region, onto its centre, release it, back away"),
    _op("take_over", {A: "arm", G: "arm", O: "object"},
        ["holding(?giver, ?obj)", "lifted(?obj)", "hand_empty(?arm)"],
        ["holding(?arm, ?obj)"], ["hand_empty(?arm)", "over(?obj, _)", "over_place(?obj, _)"],
        [{"name": "move_to_target", "args": {"arm": G, "xyz": HANDOVER_XYZ, "rpy_deg": DOWN_RPY}},
         {"name": "move_to_obj", "args": {"arm": A, "obj": O,
                                          "offset": [0.0, f"$mirror(?arm, -{TAKE_REACH_M})", TAKE_HIGH_M],
                                          "rpy_deg": ["$mirror(?arm, -90)", 90.0, 0.0]}},
         {"name": "move_by_offset", "args": {"arm": A, "dxyz": [0.0, f"$mirror(?arm, {TAKE_REACH_M - TAKE_DEPTH_M})",
                                                                0.0]}},
         {"name": "close_gripper", "args": {"arm": A}}], 330,
        "first half of a handover: the giving arm presents the held object between the arms, the other comes "
        "in side-on and closes on it (both now hold it)"),
    _op("let_go", {G: "arm", A: "arm", O: "object"},
        ["holding(?giver, ?obj)", "holding(?arm, ?obj)"],
        ["hand_empty(?giver)", "handed_over(?obj, ?giver, ?arm)"], ["holding(?giver, ?obj)"],
        [{"name": "open_gripper", "args": {"arm": G}},
         {"name": "move_by_offset", "args": {"arm": G, "dxyz": [0.0, 0.0, GIVER_CLEAR_M]}}], 90,
        "second half of a handover: the giving arm opens and moves clear, the other keeps the object"),
    _op("put_inside", {A: "arm", O: "object", C: "object"},
        ["holding(?arm, ?obj)", "lifted(?obj)", "upright(?obj)", "flat(?box)", "on_table(?box)",
         "not moved(?box)", "not inside(?box, ?obj)"],
        ["inside(?obj, ?box)", "released(?obj)", "hand_empty(?arm)"],
        ["holding(?arm, ?obj)", "lifted(?obj)", "over(?obj, _)", "over_place(?obj, _)"],
        [{"name": "place", "args": {"arm": A, "x": f"$x({C}, {INSIDE_AT_M})", "y": f"$y({C})",
                                    "z_offset": INSIDE_FLOOR_M}},
         {"name": "back", "args": {"arm": A}}], 300,
        "lower the held upright object into a flat open container where it was first seen, release, back away"),
    _op("take_both", {O: "object"},
        ["hand_empty(left)", "hand_empty(right)", "not narrow(?obj)", "released(?obj)", "on_table(?obj)",
         "flat(?obj)"],
        ["holding(left, ?obj)", "holding(right, ?obj)"], ["hand_empty(left)", "hand_empty(right)", "released(?obj)"],
        [_both({"name": "grasp", "args": {"obj": O, "pre_grasp_offset": 0.05}},
               {"left": {"grasp_offset": [RIM_FORWARD_M, f"$hy({O}, -{RIM_INSET_M})", RIM_HOLD_Z_M]},
                "right": {"grasp_offset": [RIM_FORWARD_M, f"$nhy({O}, -{RIM_INSET_M})", RIM_HOLD_Z_M]}})], 260,
        "both arms take a flat object too wide for one hand by its side rims (one dual grasp, wherever it lies "
        "now: the rims are found on the perceived object)"),
    _op("carry_both", {O: "object", P: "place"},
        ["holding(left, ?obj)", "holding(right, ?obj)", "on_table(?obj)", "flat(?obj)", "region(?place)",
         "not in_region(?obj, ?place)"],
        ["in_region(?obj, ?place)", "moved(?obj)"], [],
        [_both({"name": "move_by_offset", "args": {"dxyz": [0.0, 0.0, CARRY_LIFT_M]}}),
         _both({"name": "move_by_offset", "args": {"dxyz": [f"$dx({O}, {P})", f"$dy({O}, {P})", 0.0]}}),
         _both({"name": "move_by_offset", "args": {"dxyz": [0.0, 0.0, -CARRY_LIFT_M]}})], 200,
        "both arms, holding it by its rims, lift it a little, carry it to the region's centre (the shift is "
        "re-synthesised at run time from the perceived centroid) and set it down, still holding it"),
    _op("let_go_both", {O: "object"},
        ["holding(left, ?obj)", "holding(right, ?obj)", "on_table(?obj)"],
        ["released(?obj)", "hand_empty(left)", "hand_empty(right)"],
        ["holding(left, ?obj)", "holding(right, ?obj)"],
        [_both({"name": "open_gripper", "args": {}}),
         _both({"name": "move_by_offset", "args": {"dxyz": [0.0, 0.0, 0.06]}}),
         _both({"name": "back", "args": {}})], 240,
        "both arms open on an object they hold on the table, rise clear and back away"),
]

def _beside(name: str, side: str, sign: float) -> OperatorSpec:
    other = "right_of" if side == "left_of" else "left_of"
    return _op(name, {A: "arm", O: "object", T: "object"},
               ["holding(?arm, ?obj)", "lifted(?obj)", "released(?target)", "on_table(?target)",
                f"not {side}(?obj, ?target)"],
               [f"{side}(?obj, ?target)", "beside(?obj, ?target)", "on_table(?obj)", "released(?obj)",
                "hand_empty(?arm)", "moved(?obj)"],
               ["holding(?arm, ?obj)", "lifted(?obj)", "over(?obj, _)", "over_place(?obj, _)",
                f"{other}(?obj, ?target)"],
               [{"name": "place", "args": {"arm": A, "x": "$x(?target)", "y": f"$y(?target, {sign * SIDE_AIM_M})"}},
                {"name": "back", "args": {"arm": A}}], 300,
               f"set the held object down {SIDE_AIM_M} m to the {side.split('_')[0]} of the target (where the target "
               "is perceived when the place runs), release it, back away")


def _by_reach(ops: list[OperatorSpec]) -> list[OperatorSpec]:
    """Each one-arm operator that takes an object from the table, twice: by the nearer arm, and by the other at
    FAR_COST more; both only when the arm reaches the object. Same name: the plan reads the same."""
    out = []
    for op in ops:
        takes = "released(?obj)" in op.pre and list(op.params.values()).count("arm") == 1 and A in op.params
        if not takes:
            out.append(op)
            continue
        pre = [*op.pre, "reaches(?arm, ?obj)"]
        out.append(op.model_copy(update={"pre": [*pre, "nearer(?arm, ?obj)"]}))
        out.append(op.model_copy(update={"pre": [*pre, "not nearer(?arm, ?obj)"], "cost": op.cost + FAR_COST}))
    return out


OPERATORS[:] = _by_reach(OPERATORS)
OPERATORS += [
    _op("stack", {A: "arm", O: "object", C: "object"},
        ["holding(?arm, ?obj)", "lifted(?obj)", "released(?box)", "on_table(?box)", "flat(?box)",
         "not on(?box, ?obj)"],
        ["on(?obj, ?box)", "released(?obj)", "hand_empty(?arm)", "moved(?obj)"],
        ["holding(?arm, ?obj)", "lifted(?obj)", "over(?obj, _)", "over_place(?obj, _)"],
        [{"name": "place", "args": {"arm": A, "x": "$x(?box)", "y": "$y(?box)", "z_offset": "$top(?box)"}},
         {"name": "back", "args": {"arm": A, "rise_m": STACK_RISE_M}}], 300,
        "set the held object down on top of a flat-topped object on the table (centred on it, its bottom at the "
        "support's top, where the support is perceived when the place runs), release it, rise, back away"),
    _beside("put_left_of", "left_of", 1.0),
    _beside("put_right_of", "right_of", -1.0),
]

TABLETOP_DOMAIN = Domain(predicates=PREDICATES, operators=OPERATORS,
                         relative_places={"beside_left": (0.0, BESIDE_M), "beside_right": (0.0, -BESIDE_M)},
                         max_grasp_width_m=0.10,
                         directions={"away": 0.0, "toward": 180.0, "leftward": 90.0, "rightward": -90.0},
                         aliases={"held_up": ["lifted(?x)", "not released(?x)"]},
                         arm_bases=ARM_BASES, reach_m=REACH_M)
