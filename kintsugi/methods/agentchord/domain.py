"""The tabletop atomic actions (paper Table IV) written as a planning domain: predicates with the
feature constraints that check them, operators with preconditions, effects, action templates and costs.

This is what the composer is told about the action library (a model reads it in the request, the
embedded planner searches it); it names no task. Costs are nominal control steps (10 ms each) at the
configured motion speeds, used for Eq. 8's cost-to-go.
"""

from __future__ import annotations

from kintsugi.reasoning.taskgraph_types import Domain, OperatorSpec, PredicateSpec

LIFT_M = 0.12
POUR_SIDE_M = 0.10
"""While pouring, the grasp point sits this far beside the target, on the pouring arm's side."""
POUR_HEIGHT_M = 0.14
POUR_DEG = 100.0
SIDE_FORWARD_RPY = [0.0, 90.0, 0.0]
"""Gripper horizontal, pointing +x: carries an upright object side-on."""


def _p(name, params, meaning, constraints=(), gripper=None) -> PredicateSpec:  # noqa: ANN001
    return PredicateSpec(name=name, params=list(params), meaning=meaning, constraints=list(constraints),
                         gripper=gripper)


PREDICATES = [
    _p("hand_empty", ["arm"], "the arm's gripper is open and holds nothing", gripper="open"),
    _p("holding", ["arm", "object"], "the arm holds the object between its fingers",
       [{"kind": "detached", "arm": "?1", "object": "?2", "tol": 0.08},
        {"kind": "touching", "arm": "?1", "object": "?2"}], gripper="closed"),
    _p("on_table", ["object"], "the object rests on the table",
       [{"kind": "in_region", "point": {"entity": "?1", "feature": "bottom"},
         "lo": [-2.0, -2.0, -0.02], "hi": [2.0, 2.0, 0.03]}]),
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
]


def _op(name, params, pre, add, delete, actions, cost, description) -> OperatorSpec:  # noqa: ANN001
    return OperatorSpec(name=name, params=params, pre=pre, add=add, delete=delete, actions=actions, cost=cost,
                        description=description)


A, O, T = "?arm", "?obj", "?target"
OPERATORS = [
    _op("grasp", {A: "arm", O: "object"},
        ["hand_empty(?arm)", "upright(?obj)", "on_table(?obj)", "released(?obj)"],
        ["holding(?arm, ?obj)"], ["hand_empty(?arm)", "released(?obj)"],
        [{"name": "grasp", "args": {"arm": A, "obj": O, "pre_grasp_offset": 0.08}}], 260,
        "open, approach an upright object side-on from its pre-grasp pose, close on it"),
    _op("lift", {A: "arm", O: "object"}, ["holding(?arm, ?obj)", "on_table(?obj)"],
        ["lifted(?obj)"], ["on_table(?obj)"],
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
]

TABLETOP_DOMAIN = Domain(predicates=PREDICATES, operators=OPERATORS)
