"""The arranger's failure-mode knowledge base, keyed by atomic action type, and where each mode can strike.

Each `FailureMode` says during which atomic actions it happens, the monitor that sees it (a constraint
template over the features, > 0 = violated, with margin and persistence window) and the symbolic state
it leaves, from which the planner finds the way back (`arranger`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from kintsugi.methods.agentchord.symbolic import State

CARRY_ACTIONS = frozenset({"move_by_offset", "move_to_obj", "move_to_target", "rotate_eef", "drive", "place"})
"""Atomic actions during which a held object can be dropped or slip (`place` lets go on purpose: it is watched
only while the hand is still commanded closed)."""
EMPTY_GRIP_M = 0.01
"""Fingers closed to less than this have nothing between them (every graspable object is wider)."""
SLIP_TOL_M = 0.08
"""A held object's centroid farther than this from the grasp point has slipped in the hand."""
MOVED_TOL_M = 0.03
TOPPLE_TOL_DEG = 30.0


@dataclass(frozen=True)
class FailureMode:
    """One entry of the knowledge base: when it applies, its monitor, and what it leaves behind."""

    name: str
    actions: frozenset[str]
    """Atomic action types it can happen during."""
    needs: str
    """`held`: an object held in the edge's source state; `target`: the object an action reaches for."""
    check: Callable[[str, str], dict]
    margin: float
    window: int
    after: Callable[[State, str, str], State]
    """Predicted symbolic state after the failure, from the failure context's state."""
    why: str


def _drop(s: State, arm: str, obj: str) -> State:
    """The object fell: the hand is empty (the gripper closes on nothing), the object lies on the table,
    nothing about it being lifted, over or tilted holds; we assume it landed upright (if it toppled, the
    `toppled` monitor of the next grasp sees it)."""
    holders = {a[1] for a in s if a[0] == "holding" and a[2] == obj} | {arm}
    keep = {a for a in s if not (a[0] in ("holding",) and a[1] == arm)
            and not (a[0] == "holding" and a[2] == obj)  # an object two arms carry falls from both
            and not (a[0] in ("lifted", "over", "over_place", "tilted") and a[1] == obj)}
    # A lying object (a fork, a block) lands lying, keeping its heading; anything else we assume upright.
    pose = ("flat", obj) if ("flat", obj) in s and ("upright", obj) not in s else ("upright", obj)
    return frozenset(keep | {("hand_empty", a) for a in holders} | {("on_table", obj), ("released", obj), pose})


KNOCKED = frozenset({"missed_grasp", "object_moved", "toppled"})
"""Grasp-time failures after which a standing object may lie knocked over (a `knock`) or still stand where it
was pushed (a `shift`): the recovery first lets it come to rest, then stands it up or re-grasps it where it is."""
LANDED_DEG = 10.0
"""After a fall, an object whose axis is within this of vertical landed standing (no looser than a judge of
uprightness is likely to be: the tabletop scorers allow 10 degrees), else lying (or leaning: it is stood up
the same way)."""


def outcomes(mode: FailureMode, s: State, arm: str, obj: str) -> list[tuple[str, State, list[dict]]]:
    """What the failure may leave, each with the guard (over perceived features) that tells it apart at run
    time: an object that stands on a base (`stands`) and falls may land standing or lying on its side."""
    after = mode.after(s, arm, obj)
    if ("stands", obj) not in s or not (mode.after is _drop or mode.name in KNOCKED):
        return [("", after, [])]
    if mode.name in KNOCKED:  # a grasp that missed or met a moved or toppled object: it may lie knocked over
        after = frozenset(after | {("upright", obj)})
    lying = frozenset(a for a in after if a != ("upright", obj))
    return [("standing", after, [{"kind": "upright", "object": obj, "tol_deg": LANDED_DEG}]),
            ("lying", lying, [{"kind": "tilted", "object": obj, "min_deg": LANDED_DEG}])]


def _unchanged(s: State, arm: str, obj: str) -> State:
    return s


def _toppled(s: State, arm: str, obj: str) -> State:
    return frozenset(a for a in s if a != ("upright", obj))


FAILURES: tuple[FailureMode, ...] = (
    FailureMode("missed_grasp", frozenset({"grasp"}), "target",
                lambda arm, obj: {"kind": "not_grasped", "arm": arm, "min_opening": EMPTY_GRIP_M}, 0.0, 3, _unchanged,
                "the fingers closed on nothing (opening below any object's width): open and grasp again"),
    FailureMode("object_moved", frozenset({"grasp"}), "target",
                lambda arm, obj: {"kind": "drift", "point": {"entity": obj}, "tol": MOVED_TOL_M, "axes": "xy"},
                0.0, 3, _unchanged,
                "the object slid away from where it was seen at the edge start: grasp it where it is now"),
    FailureMode("toppled", frozenset({"grasp"}), "target",
                lambda arm, obj: {"kind": "upright", "object": obj, "tol_deg": TOPPLE_TOL_DEG}, 0.0, 3, _toppled,
                "the object was knocked over: it must be stood up before a side grasp"),
    FailureMode("drop", CARRY_ACTIONS, "held",
                lambda arm, obj: {"kind": "touching", "arm": arm, "object": obj, "expect": True}, 0.0, 3, _drop,
                "the held object fell out of the hand (the finger pads no longer touch it): pick it up and carry on"),
    FailureMode("slip", CARRY_ACTIONS - {"place"}, "held",
                lambda arm, obj: {"kind": "detached", "arm": arm, "object": obj, "tol": SLIP_TOL_M}, 0.01, 5, _drop,
                "the held object slid out of the grasp point: treat as dropped, pick it up and carry on"),
)
"""Failure modes per atomic action type. IK infeasibility is not a feature-level failure: the conductor
reports an unreachable keyframe as a recorded failure with the solver's message."""


def arm_calls(edge: Any) -> list[tuple[str, dict]]:
    """(action name, arguments) of the edge's per-arm calls: a dual `drive` counts as its two arm actions (a
    two-arm grasp can miss like a one-arm one)."""
    out = []
    for a in edge.actions:
        out.append((a.name, a.args))
        if a.name == "drive":
            out += [(v["action"], v) for v in a.args.values() if isinstance(v, dict) and isinstance(v.get("action"), str)]
    return out


def _candidates(mode: FailureMode, edge: Any, u: State, v: State | None = None) -> list[tuple[str, str]]:
    calls = arm_calls(edge)
    kinds = {name for name, _ in calls}
    if not kinds & mode.actions:
        return []
    if mode.needs == "held":  # an edge that lets go on purpose (a handover's giver) is not watched for a drop
        held = [(a[1], a[2]) for a in u if a[0] == "holding" and (v is None or a in v or _placed_by(edge, a[1]))]
        if mode.name == "slip":  # two arms hold a wide object by its rims, far from its centroid by design
            held = [(arm, o) for arm, o in held if sum(1 for _, p in held if p == o) == 1]
        return sorted(held)
    out = []
    for name, args in calls:
        if name in mode.actions and isinstance(args.get("arm"), str) and isinstance(args.get("obj"), str):
            if mode.name == "toppled" and ("upright", args["obj"]) not in u:
                continue  # only what stands can topple (a lying fork's axis is horizontal by design)
            if mode.name == "missed_grasp" and ("narrow", args["obj"]) not in u:
                continue  # a wide object is taken by a thin rim: a closed hand is no sign of a miss (the pads,
                # watched as a drop on the next edge, are)
            if (args["arm"], args["obj"]) not in out:
                out.append((args["arm"], args["obj"]))
    return out


def _placed_by(edge: Any, arm: str) -> bool:
    """The edge lets the arm's object go by a `place` (lowered, then released): a drop before the release is a
    failure (watched while the hand is commanded closed, `touching.while_closed`)."""
    return any(a.name == "place" and a.args.get("arm") == arm for a in edge.actions)
