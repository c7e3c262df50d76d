"""The composer role (AgentChord Eq. 2): instruction + first observation -> nominal task graph.

`embedded_compose` plans, it does not follow a per-task script: it reads the observed state as facts
(what perception and the arms' sensors report), parses the task's goal predicates, grounds the domain's
operators over the scene and searches for the cheapest plan (`symbolic.plan`). Each step becomes an edge
(its atomic actions, cost in control steps) into a sub-goal node whose constraints check the facts the step
made true. `ask_compose` runs the role on any backend and checks the reply into a `TaskGraph`.
"""

from __future__ import annotations

import re
from typing import Any

from kintsugi.reasoning.jsontext import BadReply
from kintsugi.methods.agentchord.symbolic import Atom, GroundOp, PlanningError, State, atom_text, ground, parse_literals, plan
from kintsugi.methods.agentchord.types import ComposerReply, ComposerRequest, Domain, SeenObject
from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.model import TaskGraph
from kintsugi.taskgraph.vocabulary import Vocabulary

ON_TABLE_Z_M = 0.03
"""An object whose lowest point is this close to the table top stands on it."""
UPRIGHT_HEIGHT_RATIO = 0.6
"""Undecided uprightness: a standing cup is ~0.7 as tall as its largest extent, a fallen bottle ~0.3."""
LIFTED_Z_M = 0.05
"""A held object whose lowest point is this high is clear of the table."""
_FN = re.compile(r"^\$(x|y|z|hy|nhy|rx|ry|yaw|mirror|thin)\(\s*(\?[A-Za-z0-9_]+)\s*(?:,\s*(-?[0-9.eE+-]+)\s*)?\)$")
_FN2 = re.compile(r"^\$(dx|dy|turn)\(\s*(\?[A-Za-z][A-Za-z0-9_]*)\s*,\s*(\?[A-Za-z][A-Za-z0-9_]*)\s*\)$")
FLAT_RATIO = 1.1
"""An object no taller than this times its middle extent lies flat (a fork, a tray, a cube; not a standing bottle)."""
HEADING_TOL_DEG = 10.0
"""Used only when the domain's `heading` predicate states no tolerance of its own."""


class GoalHolds(PlanningError):
    """Planning found nothing to do: the observed scene already satisfies the goal."""


def observed_facts(request: Any, domain: Domain, places: list[str] = ()) -> State:
    """Facts read off the observation, for the predicates the domain declares (closed world: the rest are
    false): hand_empty/holding from the arms' pads, upright from perception's uprightness, on_table from the
    object's lowest point (lifted: held and clear of it), released when no arm holds it."""
    known = {p.name for p in domain.predicates}
    held = {o: a.name for a in request.arms for o in a.holding}
    facts: set[Atom] = set()
    for a in request.arms:
        if "hand_empty" in known and not a.holding:
            facts.add(("hand_empty", a.name))
        if "holding" in known:
            facts |= {("holding", a.name, o) for o in a.holding}
    for o in request.objects:
        if not o.visible:
            continue
        if "upright" in known and looks_upright(o):
            facts.add(("upright", o.name))
        if "on_table" in known and o.bottom_z is not None and o.bottom_z < ON_TABLE_Z_M and o.name not in held:
            facts.add(("on_table", o.name))
        if "lifted" in known and o.bottom_z is not None and o.bottom_z > LIFTED_Z_M and o.name in held:
            facts.add(("lifted", o.name))
        if "released" in known and o.name not in held:
            facts.add(("released", o.name))
        if "stands" in known and o.upright:
            facts.add(("stands", o.name))
        if "narrow" in known and o.extent is not None and sorted(o.extent)[1] < domain.max_grasp_width_m:
            facts.add(("narrow", o.name))
        if "flat" in known and looks_flat(o):
            facts.add(("flat", o.name))
        if "heading" in known:
            yaw, tol = head_yaw_deg(o), heading_tol_deg(domain)
            facts |= {("heading", o.name, d) for d, psi in domain.directions.items()
                      if yaw is not None and abs(wrap_deg(yaw - psi)) <= tol}
    for p in places:
        if "direction" in known and p in domain.directions:
            facts.add(("direction", p))
        elif "region" in known:
            facts.add(("region", p))
    return frozenset(facts)


def heading_tol_deg(domain: Domain) -> float:
    """The tolerance the domain's own `heading` check uses: the first observation must read the fact exactly as
    the sub-goal node will check it, or a plan skips a turn its node then refuses."""
    for p in domain.predicates:
        for c in p.constraints if p.name == "heading" else ():
            if c.get("kind") == "heading" and isinstance(c.get("tol_deg"), (int, float)):
                return float(c["tol_deg"])
    return HEADING_TOL_DEG


def remembered_facts(request: Any, domain: Domain) -> State:
    """The domain's static facts (`PredicateSpec.static`: shape and size, not pose) that the task's first
    observation showed about the objects still in the scene, when a re-planning request carries it: a bottle seen
    standing still `stands` after it fell over, though its lying view does not show it."""
    from types import SimpleNamespace

    first = getattr(request, "first_objects", None)
    if not first:
        return frozenset()
    static = {p.name for p in domain.predicates if p.static}
    now = {o.name for o in request.objects}
    seen = SimpleNamespace(arms=[], objects=[o for o in first if o.name in now])
    return frozenset(a for a in observed_facts(seen, domain) if a[0] in static)


def looks_flat(o: SeenObject) -> bool:
    if o.top_z is None or o.bottom_z is None or o.extent is None:
        return False
    # extent: along the principal axis, then across it; a standing bottle is taller than its second extent.
    return o.top_z - o.bottom_z <= FLAT_RATIO * sorted(o.extent)[1]


def wrap_deg(d: float) -> float:
    return (d + 180.0) % 360.0 - 180.0


def head_yaw_deg(o: SeenObject) -> float | None:
    """Yaw of a long object's head from its perceived axis ends: the wide head pulls the point cloud's centroid
    towards it, so the axis end nearer the centroid is the head. None without axis ends."""
    import math

    ends = [o.extremes.get(k) for k in ("axis_pos", "axis_neg")]
    if o.centroid is None or any(e is None for e in ends):
        return None
    c = o.centroid
    near, far = sorted(ends, key=lambda e: math.hypot(e[0] - c[0], e[1] - c[1]))
    return math.degrees(math.atan2(near[1] - far[1], near[0] - far[0]))


def goal_places(goal: list[str], arms: list[str], objects: list[str]) -> list[str]:
    """The goal's constants that name no arm or object: regions (`target`, `beside_left(plate)`), directions."""
    from kintsugi.methods.agentchord.types import parse_atom

    out: list[str] = []
    for text in goal:
        for a in parse_atom(text)[2]:
            if a not in arms and a not in objects and a not in out and not a.startswith("?") and a != "_":
                out.append(a)
    return out


def place_xy(place: str, domain: Domain, seen: dict[str, SeenObject], regions: dict) -> tuple[float, float]:
    """A region's centre: a named region of the task statement, or `fn(obj)` from the object's perceived centroid."""
    if place in regions:
        return tuple(float(v) for v in regions[place])
    m = re.fullmatch(r"([A-Za-z][A-Za-z0-9_]*)\(([A-Za-z][A-Za-z0-9_]*)\)", place)
    if m and m.group(1) in domain.relative_places:
        o = seen.get(m.group(2))
        if o is None or o.centroid is None:
            raise PlanningError(f"place {place!r}: object {m.group(2)!r} was not perceived")
        dx, dy = domain.relative_places[m.group(1)]
        return o.centroid[0] + dx, o.centroid[1] + dy
    raise PlanningError(f"place {place!r} is neither a region of the task ({', '.join(regions) or 'none'}) nor "
                        f"one of {', '.join(f'{k}(object)' for k in domain.relative_places) or 'no place functions'}")


def looks_upright(o: SeenObject) -> bool:
    """Perception's uprightness; when it could not decide (no well-defined axis), an object at least as tall
    as it is long stands upright."""
    if o.upright is not None:
        return o.upright
    if o.top_z is None or o.bottom_z is None or o.extent is None:
        return False
    return o.top_z - o.bottom_z >= UPRIGHT_HEIGHT_RATIO * max(o.extent)


def arms_named(task: str, arms: list[str]) -> list[str]:
    """The arms an instruction asks for ("using the right arm"); all arms when it names none or both."""
    text = task.lower()
    named = [a for a in arms if re.search(rf"\b{a}\s+(arm|hand)\b", text)]
    return named or list(arms)


def arm_bindings(task: str, arms: list[str], objects: list[str]) -> dict[str, str]:
    """Objects the instruction gives to one arm ("the cup with the left arm", "the bottle with the right
    hand") -> that arm. "using the right arm" after a phrase names the arm for the whole task (`arms_named`),
    not for the object before it."""
    text = task.lower()
    out = {}
    for o in objects:
        for a in arms:
            if (re.search(rf"\b{re.escape(o.lower())}\s+with\s+(the\s+)?{a}\s+(arm|hand)\b", text)
                    or re.search(rf"\b{a}\s+(arm|hand)\s+for\s+(the\s+)?{re.escape(o.lower())}\b", text)):
                out[o] = a
    return out


def held_up(task: str, objects: list[str]) -> list[str]:
    """Objects the instruction asks to be held up while others act on them ("hold the cup up")."""
    text = task.lower()
    return [o for o in objects if re.search(rf"\bhold\s+(the\s+)?{re.escape(o.lower())}\s+up\b", text)]


def instructed_ops(task: str, domain: Any, arms: list[str], objects: list[str], places: list[str] = ()) -> list:
    """The grounded operators the instruction allows: an object given to one arm is taken from the table by
    that arm only (no instance that picks it up adds holding(other arm, it); a handover may pass it on), until
    it has handed the object over to the other arm: from then on only the taker picks it up again after a
    drop (the giver may not reach where it fell); an object to be held up must be lifted before any operator makes a fact that
    names it as the target (carry over it, pour into it)."""
    from dataclasses import replace

    bound, up = arm_bindings(task, arms, objects), held_up(task, objects)
    handovers = any(p.name == "handed_over" and len(p.params) == 3 for p in domain.predicates)
    out = []
    for op in ground(domain, arms, objects, places):
        other = _other_taker(op, bound) or _other_hand(op, bound)
        if other is not None and not handovers:
            continue
        if other is not None:
            arm, obj = other
            op = replace(op, pre_pos=op.pre_pos | {("handed_over", obj, bound[obj], arm)})
        elif handovers and (own := _own_take(op, bound)) is not None:  # once handed over, the taker's object
            arm, obj = own
            op = replace(op, pre_neg=op.pre_neg | {("handed_over", obj, arm, b) for b in arms if b != arm})
        targets = {a[2] for a in op.add if len(a) == 3 and a[1] in objects and a[2] in up}
        if targets:
            op = replace(op, pre_pos=op.pre_pos | {("lifted", t) for t in targets})
        out.append(op)
    return out


def _other_taker(op: Any, bound: dict[str, str]) -> tuple[str, str] | None:
    """(arm, object) when the operator alone takes from the table an object the instruction gives to another
    arm (a two-arm take is not the other arm taking it alone)."""
    takers: dict[str, int] = {}
    for a in op.add:
        if a[0] == "holding":
            takers[a[2]] = takers.get(a[2], 0) + 1
    for a in op.add:
        if (a[0] == "holding" and a[2] in bound and bound[a[2]] != a[1] and ("released", a[2]) in op.pre_pos
                and takers[a[2]] == 1):
            return a[1], a[2]
    return None


def _own_take(op: Any, bound: dict[str, str]) -> tuple[str, str] | None:
    """(arm, object) for a one-arm operator by the arm the instruction gives the object to, on it lying free."""
    b = dict(op.binding)
    arm, obj = b.get("?arm"), b.get("?obj")
    if (arm is not None and bound.get(obj) == arm and ("released", obj) in op.pre_pos
            and sum(1 for v in op.spec.params.values() if v == "arm") == 1):
        return arm, obj
    return None


def _other_hand(op: Any, bound: dict[str, str]) -> tuple[str, str] | None:
    """(arm, object) for a one-arm operator that handles an object lying free (`released` before it) which the
    instruction gives to the other arm (standing a fallen bottle up is the bottle's arm's job, as taking it is)."""
    b = dict(op.binding)
    arm, obj = b.get("?arm"), b.get("?obj")
    if (arm is not None and obj in bound and bound[obj] != arm and ("released", obj) in op.pre_pos
            and sum(1 for v in op.spec.params.values() if v == "arm") == 1):
        return arm, obj
    return None


def fill(value: Any, binding: dict[str, str], seen: dict[str, SeenObject], where: Any = None) -> Any:
    """Instantiate a template: `?p` -> its value, `$x(?obj[, d])` -> the object's perceived centroid x (y, z)
    plus d, `$hy(?obj, d)` / `$nhy` -> +/- (half its perceived y extent + d), `$rx(?place)` / `$ry` -> the
    region's centre, `$dx(?obj, ?place)` / `$dy` -> region centre minus the object's centroid, `$turn(?obj,
    ?dir)` -> the turn about the vertical bringing the object's head to the direction, `$yaw(?dir)` -> the
    direction's yaw (degrees), `$thin(?obj, d)` -> its thinnest perceived span plus d, `$mirror(?arm, v)` -> v
    for the right arm, -v for the left; lists and dicts
    recursively. `where`: place -> (x, y)."""
    if isinstance(value, dict):
        return {k: fill(v, binding, seen, where) for k, v in value.items()}
    if isinstance(value, list):
        return [fill(v, binding, seen, where) for v in value]
    if not isinstance(value, str):
        return value
    if value in binding:
        return binding[value]
    m2 = _FN2.match(value)
    if m2:
        return _fill2(value, m2.groups(), binding, seen, where or {})
    m = _FN.match(value)
    if not m:
        return value
    fn, param, num = m.groups()
    if param not in binding:
        raise PlanningError(f"template {value!r} names undeclared parameter {param}")
    arg = binding[param]
    if fn == "mirror":
        if num is None:
            raise PlanningError(f"template {value!r} needs a number: $mirror(?arm, v)")
        return float(num) if arg == "right" else -float(num)
    d = float(num) if num is not None else 0.0
    if fn in ("rx", "ry"):
        return round(_where(value, arg, where or {})["xy".index(fn[1])] + d, 4)
    if fn == "yaw":
        psi = (where or {}).get(("direction", arg))
        if psi is None:
            raise PlanningError(f"template {value!r}: {arg!r} is not a known direction")
        return round(float(psi) + d, 3)
    obj = seen.get(arg)
    if fn in ("hy", "nhy", "thin"):
        if obj is None or obj.extent is None:
            raise PlanningError(f"template {value!r}: object {arg!r} has no perceived extent")
        if fn == "thin":  # its thinnest perceived span (its thickness, however it lies) plus d
            return round(min(obj.extent) + d, 4)
        half = obj.extent[1] / 2.0 + d
        return round(half if fn == "hy" else -half, 4)
    if obj is None or obj.centroid is None:
        raise PlanningError(f"template {value!r}: object {arg!r} was not perceived, so its position is unknown")
    return round(float(obj.centroid["xyz".index(fn)]) + d, 4)


def _where(value: str, place: str, where: dict) -> tuple[float, float]:
    if place not in where:
        raise PlanningError(f"template {value!r}: {place!r} is not a known region")
    return where[place]


def _fill2(value: str, groups: tuple, binding: dict[str, str], seen: dict[str, SeenObject], where: dict) -> float:
    fn, p1, p2 = groups
    for p in (p1, p2):
        if p not in binding:
            raise PlanningError(f"template {value!r} names undeclared parameter {p}")
    obj = seen.get(binding[p1])
    if obj is None or obj.centroid is None:
        raise PlanningError(f"template {value!r}: object {binding[p1]!r} was not perceived")
    if fn == "turn":
        yaw = head_yaw_deg(obj)
        psi = where.get(("direction", binding[p2]))
        if yaw is None or psi is None:
            raise PlanningError(f"template {value!r}: no perceived head for {binding[p1]!r} or unknown direction")
        # A gripper pointing down turns the held object by minus its own turn about the approach axis.
        return round(wrap_deg(yaw - psi), 3)
    xy = _where(value, binding[p2], where)
    i = "xy".index(fn[1])
    return round(xy[i] - float(obj.centroid[i]), 4)


def _positional(binding: dict[str, str], args: tuple[str, ...]) -> dict[str, str]:
    return {f"?{i + 1}": v for i, v in enumerate(args)}


def node_constraints(domain: Domain, atoms: list[Atom], seen: dict[str, SeenObject], where: Any = None
                     ) -> tuple[list, dict]:
    """Constraints and gripper states checking the given facts on a sub-goal node."""
    specs = {p.name: p for p in domain.predicates}
    constraints: list = []
    gripper: dict[str, str] = {}
    shared = _held_by_two(atoms)
    for a in atoms:
        spec = specs[a[0]]
        b = _positional({}, a[1:])
        cs = [c for c in spec.constraints if not (a[0] == "holding" and a[2] in shared and c.get("kind") == "detached")]
        constraints += [fill(c, b, seen, where) for c in cs]
        if spec.gripper is not None and spec.params and spec.params[0] == "arm":
            gripper[a[1]] = spec.gripper
    return constraints, gripper


def _held_by_two(atoms: list[Atom]) -> set[str]:
    """Objects two arms hold at once: taken by their rims, far from the centroid by design, so the centroid's
    distance from either hand (`detached`) says nothing about the grasp; the pads (`touching`) still do."""
    count: dict[str, int] = {}
    for a in atoms:
        if a[0] == "holding" and len(a) == 3:
            count[a[2]] = count.get(a[2], 0) + 1
    return {o for o, n in count.items() if n > 1}


def edge_actions(op: GroundOp, seen: dict[str, SeenObject], where: Any = None) -> list:
    return [fill(a, dict(op.binding), seen, where) for a in op.spec.actions]


def build_graph(task: str, domain: Domain, initial: State, steps: list[GroundOp],
                seen: dict[str, SeenObject], goal: frozenset[Atom] = frozenset(), where: Any = None) -> ComposerReply:
    """A chain graph start -> s1 -> ... -> goal from a plan, with the symbolic state of every node. The goal
    node checks every goal fact (not only the last step's), so the verdict covers the whole task."""
    if not steps:
        raise GoalHolds("the goal already holds in the observed scene; there is nothing to do")
    nodes = [{"id": "start", "description": "the observed scene"}]
    edges = []
    facts = {"start": sorted(atom_text(a) for a in initial)}
    operators = {}
    state, prev = initial, "start"
    for i, op in enumerate(steps, 1):
        after = op.apply(state)
        made = sorted(after - state)
        if i == len(steps):
            made = sorted(set(made) | set(goal))
        constraints, gripper = node_constraints(domain, made, seen, where)
        nid, eid = f"s{i}_{op.name}", f"e{i}_{op.name}"
        nodes.append({"id": nid, "description": ", ".join(atom_text(a) for a in made) or op.label,
                      "constraints": constraints, "gripper": gripper})
        edges.append({"id": eid, "source": prev, "target": nid, "actions": edge_actions(op, seen, where),
                      "cost": op.cost, "description": op.label})
        facts[nid] = sorted(atom_text(a) for a in after)
        operators[eid] = op.label
        state, prev = after, nid
    graph = {"task": task, "start": "start", "goal": prev, "nodes": nodes, "edges": edges}
    why = "plan: " + " -> ".join(op.label for op in steps)
    return ComposerReply(graph=graph, node_facts=facts, edge_operators=operators, reasoning=why)


def _short(exc: Exception, limit: int = 800) -> str:
    """An error short enough to quote back to a model (hostile replies can make pydantic echo huge values)."""
    text = str(exc)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def embedded_compose(request: ComposerRequest) -> ComposerReply:
    """Plan the nominal graph from the goal predicates and the observed facts (no task script)."""
    domain = request.domain
    seen = {o.name: o for o in request.objects}
    arms = arms_named(request.task, [a.name for a in request.arms])
    names = [o.name for o in request.objects if o.visible]
    places = goal_places(list(request.goal), [a.name for a in request.arms], [o.name for o in request.objects])
    where = place_table(places, domain, seen, dict(request.regions))
    initial = observed_facts(request, domain, places) | remembered_facts(request, domain)
    goal = parse_literals(list(request.goal), domain, where="task goal")
    ops = instructed_ops(request.task, domain, arms, names, places)
    steps = plan(initial, goal, ops)
    return build_graph(request.task, domain, initial, steps, seen, goal[0], where)


def place_table(places: list[str], domain: Domain, seen: dict[str, SeenObject], regions: dict) -> dict:
    """place -> region centre (x, y); ("direction", d) -> yaw for the directions."""
    out: dict = {}
    for p in places:
        if p in domain.directions:
            out[("direction", p)] = domain.directions[p]
        else:
            out[p] = place_xy(p, domain, seen, regions)
    return out


def check_composition(reply: ComposerReply, vocabulary: Vocabulary) -> TaskGraph:
    """The reply's graph, parsed and checked against the task's vocabulary; BadReply names what is wrong
    (so an endpoint gets one repair round)."""
    try:
        graph = TaskGraph.from_data(reply.graph, vocabulary)
    except GraphError as exc:
        raise BadReply(f"the task graph is unusable: {_short(exc)}") from None
    stray = [k for k in (*reply.node_facts, *reply.edge_operators) if k not in graph.node_map and k not in graph.edge_map]
    if stray:
        raise BadReply(f"node_facts/edge_operators name {stray[0]!r}, which is not a node or edge of the graph")
    nominal = [n for n in graph.nodes if n.kind != "nominal"] + [e for e in graph.edges if e.kind != "nominal"]
    if nominal:
        raise BadReply(f"the composer's graph must be nominal; {nominal[0].id!r} is a recovery element "
                       "(recovery branches are the arranger's job)")
    return graph


def ask_compose(reasoner: Any, request: ComposerRequest, vocabulary: Vocabulary) -> tuple[TaskGraph, ComposerReply]:
    """The composer role on any backend (recorded when the reasoner records) -> a checked nominal graph."""
    from kintsugi.reasoning.roles import ask_role

    out: dict[str, TaskGraph] = {}

    def check(reply: ComposerReply) -> ComposerReply:
        out["graph"] = check_composition(reply, vocabulary)
        return reply

    reply = ask_role(reasoner, "composer", request, ComposerReply, embedded_compose, check, system="system_taskgraph")
    return out["graph"], reply


__all__ = ["GoalHolds", "ask_compose", "check_composition", "embedded_compose", "observed_facts", "PlanningError"]
