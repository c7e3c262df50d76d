"""Typed requests and replies of system B's planning roles (AgentChord): composer and arranger.

What a role sees is what a model would: the instruction, the task's goal predicates, the atomic
action library written as a planning domain (preconditions and effects, the same text a prompt
gives a model), perceived object features, the arms' own sensors, and camera images. Never the
simulator's truth. Graphs travel as plain JSON (`graph`, `proposals`) and are checked by
`kintsugi.taskgraph` after the reply parses, so a bad graph is a repairable reply, not a crash.
"""

from __future__ import annotations

import functools
import re
from typing import Annotated, Literal

from pydantic import Field, JsonValue, field_validator

from kintsugi.core.config import StrictModel

Vec3 = tuple[float, float, float]
ATOM = re.compile(r"^\s*(not\s+)?([A-Za-z][A-Za-z0-9_]*)\s*\(\s*((?:[^()]|\([^()]*\))*)\)\s*$")
"""A literal: `pred(a, b)` or `not pred(a)`; arguments are names, `?params`, `_` (any value; deletes only), or
a place term `fn(name)` (a region relative to an object, e.g. `beside_left(plate)`), kept as one constant."""
TERM = re.compile(r"\??[A-Za-z][A-Za-z0-9_]*|_|[A-Za-z][A-Za-z0-9_]*\(\s*[A-Za-z][A-Za-z0-9_]*\s*\)")
_ARG_SPLIT = re.compile(r",(?![^()]*\))")
Literal_ = Annotated[str, Field(max_length=200)]
FAILURE_MODES = ("missed_grasp", "object_moved", "toppled", "drop", "slip", "ik_infeasible")
"""The failure modes the arranger is asked to anticipate."""


@functools.lru_cache(maxsize=8192)
def parse_atom(text: str) -> tuple[bool, str, tuple[str, ...]]:
    """`not holding(?arm, bottle)` -> (False, "holding", ("?arm", "bottle")); ValueError if malformed.
    Remembered: grounding a domain parses the same few hundred literals thousands of times."""
    m = ATOM.match(text)
    if not m:
        raise ValueError(f"{text!r} is not a literal like pred(a, b) or not pred(a)")
    args = tuple(re.sub(r"\s+", "", a) for a in _ARG_SPLIT.split(m.group(3)) if a.strip())
    for a in args:
        if not TERM.fullmatch(a):
            raise ValueError(f"{text!r}: argument {a!r} is not a name, ?param, fn(name) or _ (any, in deletes)")
    return m.group(1) is None, m.group(2), args


def _atoms(v: list[str]) -> list[str]:
    for text in v:
        parse_atom(text)
    return v


class PredicateSpec(StrictModel):
    """One predicate of the domain: what it means, and the constraints (over perceived features) that
    check it on a sub-goal node; `?param` strings in the constraint templates are filled in."""

    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    params: list[Literal["arm", "object", "place"]] = Field(max_length=4)
    """`place`: a constant of the goal that names no arm or object (a region, a direction such as `away`)."""
    meaning: str = Field(default="", max_length=400)
    constraints: list[dict[str, JsonValue]] = Field(default_factory=list, max_length=8)
    """Constraint templates (kintsugi.taskgraph.constraints) with `?1`, `?2` for the arguments."""
    gripper: Literal["open", "closed"] | None = None
    """For an (arm, ...) predicate: the gripper state it implies for that arm."""
    static: bool = False
    """A property of the thing itself (its shape, its size), not of where it is or who holds it: what the first
    observation showed still holds later, when the view no longer shows it (a fallen bottle still stands)."""


class OperatorSpec(StrictModel):
    """One symbolic step (STRIPS): typed parameters, preconditions, effects, the atomic actions that
    carry it out (templates), and its physical cost in control steps."""

    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    params: dict[str, Literal["arm", "object", "place"]] = Field(max_length=4)
    """`?name` -> type."""
    pre: list[Literal_] = Field(default_factory=list, max_length=16)
    add: list[Literal_] = Field(default_factory=list, max_length=16)
    delete: list[Literal_] = Field(default_factory=list, max_length=16)
    actions: list[dict[str, JsonValue]] = Field(min_length=1, max_length=8)
    """ActionCall templates; argument strings `?p`, `$x(?obj)` / `$y` / `$z` (first perceived centroid),
    `$mirror(?arm, v)` (v for the right arm, -v for the left) are filled in when the graph is built."""
    cost: float = Field(gt=0, le=1e6)
    description: str = Field(default="", max_length=400)

    @field_validator("pre", "add", "delete")
    @classmethod
    def _literals(cls, v: list[str]) -> list[str]:
        return _atoms(v)

    @field_validator("params")
    @classmethod
    def _names(cls, v: dict[str, str]) -> dict[str, str]:
        for p in v:
            if not re.fullmatch(r"\?[A-Za-z][A-Za-z0-9_]*", p):
                raise ValueError(f"parameter {p!r} must look like ?name")
        return v


class Domain(StrictModel):
    """The atomic action library as a planning domain (shared by the prompt and the embedded planner)."""

    predicates: list[PredicateSpec] = Field(min_length=1, max_length=64)
    operators: list[OperatorSpec] = Field(min_length=1, max_length=64)
    relative_places: dict[str, tuple[float, float]] = Field(default_factory=dict, max_length=16)
    """Place functions `fn(obj)` -> a region centred this far (x, y, metres) from the object's perceived centroid."""
    max_grasp_width_m: float = Field(0.10, gt=0.0, le=1.0)
    """One gripper's widest opening: an object narrower than this (its smaller horizontal extent) is `narrow`."""
    directions: dict[str, float] = Field(default_factory=dict, max_length=16)
    """Direction names a heading goal may use -> yaw in degrees (0 = +x, away from the robot)."""
    arm_bases: dict[str, tuple[float, float]] = Field(default_factory=dict, max_length=2)
    """The robot's description: each arm's base (x, y, metres, world frame), for which arm reaches what."""
    reach_m: float = Field(0.7, gt=0.0, le=5.0)
    """How far (horizontally, from its base) an arm reaches an object on the table."""
    aliases: dict[str, list[Literal_]] = Field(default_factory=dict, max_length=16)
    """Goal words that stand for a conjunction of the domain's literals, its parameters (`?x`, ...) in order of
    appearance for the arguments: `held_up(x)` -> `lifted(x)`, `not released(x)` (in a hand, clear of the table)."""

    @field_validator("aliases")
    @classmethod
    def _alias_literals(cls, v: dict[str, list[str]]) -> dict[str, list[str]]:
        for texts in v.values():
            _atoms(texts)
        return v


class SeenObject(StrictModel):
    """One object as perception reports it (metres, degrees); None fields were not measurable."""

    name: str
    visible: bool
    centroid: Vec3 | None = None
    top_z: float | None = None
    bottom_z: float | None = None
    tilt_deg: float | None = None
    upright: bool | None = None
    extent: Vec3 | None = None
    extremes: dict[str, Vec3] = Field(default_factory=dict)
    """Named extremal points (top, bottom, axis ends, a container's opening)."""
    axis: Vec3 | None = None
    n_points: int = 0
    kind: str | None = None
    """What the task calls this kind of object (a detector's label: `can`, `block`), when it says; not measured."""
    colour: str | None = None
    """The colour the task gives the object (what the cameras show: `red`), when it says; not measured."""


class SeenArm(StrictModel):
    """One arm from its own sensors: tool position, gripper opening, commanded state, what both pads touch."""

    name: Literal["left", "right"]
    tcp_pos: Vec3
    gripper_opening_m: float
    gripper_closed: bool
    holding: list[str] = Field(default_factory=list)


class ComposerRequest(StrictModel):
    task: str = Field(description="the instruction")
    goal: list[Literal_] = Field(default_factory=list, max_length=32,
                                 description="empty: the composer reads the goal from the instruction; re-planning "
                                             "mid-task: the part of the composed goal still to reach")
    objects: list[SeenObject] = Field(min_length=1, max_length=32)
    arms: list[SeenArm] = Field(min_length=1, max_length=2)
    domain: Domain
    regions: dict[str, tuple[float, float]] = Field(default_factory=dict, max_length=16)
    """Named fixed regions of the task statement (centre x, y in metres: where the painted region is), for
    goals such as `in_region(block, target)`; regions relative to an object (`beside_left(plate)`) are
    computed from its perceived centroid instead."""
    region_sizes: dict[str, tuple[float, float]] = Field(default_factory=dict, max_length=16)
    """The half-extents (x, y, metres) the task statement gives its regions, by place (`target`,
    `beside_right(plate)`): an `in_region` check holds inside them less perception's margin. A region with
    none stated is checked within the domain's default."""
    images_png: dict[str, bytes] = Field(default_factory=dict, repr=False)
    first_objects: list[SeenObject] = Field(default_factory=list, max_length=32)
    """Re-planning mid-task: the objects as perceived in the task's first observation (empty on the first plan).
    The domain's `static` facts it showed still hold though the current view may not show them (a bottle seen
    standing, now lying, still stands); a model that planned the task first has seen that scene too."""
    first_images_png: dict[str, bytes] = Field(default_factory=dict, repr=False)
    """Re-planning: the first observation's camera images (with a model backend)."""

    @field_validator("goal")
    @classmethod
    def _literals(cls, v: list[str]) -> list[str]:
        return _atoms(v)


class ComposerReply(StrictModel):
    goal: list[Literal_] = Field(default_factory=list, max_length=32,
                                 description="the formal goal the composer read from the instruction (literals over "
                                             "the domain's predicates); the graph's goal node checks it")
    graph: dict[str, JsonValue] = Field(description="the nominal task graph (kintsugi.taskgraph JSON)")
    node_facts: dict[str, list[str]] = Field(default_factory=dict,
                                             description="node id -> the facts that hold there (optional)")
    edge_operators: dict[str, str] = Field(default_factory=dict,
                                           description="edge id -> the ground operator it carries out (optional)")
    reasoning: str = Field(default="", max_length=4000)

    @field_validator("goal")
    @classmethod
    def _literals(cls, v: list[str]) -> list[str]:
        return _atoms(v)


class ArrangerRequest(StrictModel):
    task: str
    graph: dict[str, JsonValue] = Field(description="the nominal task graph to augment")
    node_facts: dict[str, list[str]] = Field(default_factory=dict)
    edge_operators: dict[str, str] = Field(default_factory=dict)
    objects: list[SeenObject] = Field(min_length=1, max_length=32)
    arms: list[SeenArm] = Field(min_length=1, max_length=2)
    domain: Domain
    regions: dict[str, tuple[float, float]] = Field(default_factory=dict, max_length=16)
    """As in ComposerRequest: the task statement's named fixed regions."""
    region_sizes: dict[str, tuple[float, float]] = Field(default_factory=dict, max_length=16)
    """As in ComposerRequest: the half-extents the task statement gives its regions."""
    goal: list[Literal_] = Field(default_factory=list, max_length=32)
    """As in ComposerRequest: what a recovery may count as reached (`not dropped(x)`: a fall is never a place)."""
    failure_modes: list[str] = Field(default_factory=lambda: list(FAILURE_MODES))
    images_png: dict[str, bytes] = Field(default_factory=dict, repr=False)


class ArrangerReply(StrictModel):
    proposals: list[dict[str, JsonValue]] = Field(max_length=256, description="kintsugi.taskgraph RecoveryProposal "
                                                                             "objects, one per failure mode and edge")
    reasoning: str = Field(default="", max_length=4000)



class VerifyRequest(StrictModel):
    """Does a sub-goal (or a path condition) hold now? Asked at run time by the re-planning baselines."""

    task: str
    subgoal: str = Field(description="what should be true now, in words")
    constraints: list[dict[str, JsonValue]] = Field(default_factory=list, max_length=32,
                                                    description="the same as constraint templates (> 0 = violated)")
    objects: list[SeenObject] = Field(min_length=1, max_length=32)
    arms: list[SeenArm] = Field(min_length=1, max_length=2)
    images_png: dict[str, bytes] = Field(default_factory=dict, repr=False)


class VerifyReply(StrictModel):
    success: bool
    explanation: str = Field(default="", max_length=2000)
