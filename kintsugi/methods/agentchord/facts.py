"""The composer's reading of the first observation: facts of the scene for the domain's predicates, and places.

Closed world: what perception and the arms' sensors report becomes the domain's facts (hand_empty,
holding, upright, on_table, lifted, ...); the rest are false. Places (regions, directions) the goal
names get their centres from the task statement or from an object's perceived centroid.
"""

from __future__ import annotations

import re
from typing import Any

from kintsugi.methods.agentchord.angles import head_yaw_deg, wrap_deg  # noqa: F401 - part of this module's API
from kintsugi.methods.agentchord.symbolic import Atom, PlanningError, State
from kintsugi.methods.agentchord.types import Domain, SeenObject

ON_TABLE_Z_M = 0.03
"""An object whose lowest point is this close to the table top stands on it."""
UPRIGHT_HEIGHT_RATIO = 0.6
"""Undecided uprightness: a standing cup is ~0.7 as tall as its largest extent, a fallen bottle ~0.3."""
LIFTED_Z_M = 0.05
"""A held object whose lowest point is this high is clear of the table."""
FLAT_RATIO = 1.1
"""An object no taller than this times its middle extent lies flat (a fork, a tray, a cube; not a standing bottle)."""
HEADING_TOL_DEG = 10.0
"""Used only when the domain's `heading` predicate states no tolerance of its own."""


def observed_facts(request: Any, domain: Domain, places: list[str] = ()) -> State:
    """Facts read off the observation, for the predicates the domain declares (closed world: the rest are
    false): hand_empty/holding from the arms' pads, upright from perception's uprightness, on_table from the
    object's lowest point, held or not (a re-plan can find a hand closed on an object still standing on the
    table: it lifts it; lifted: held and clear of it), released when no arm holds it."""
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
        if "on_table" in known and o.bottom_z is not None and o.bottom_z < ON_TABLE_Z_M:  # held too: lift it then
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
    facts |= reach_facts(request, domain, known)
    facts |= checked_facts(request, domain, places)
    for p in places:
        if "direction" in known and p in domain.directions:
            facts.add(("direction", p))
        elif "region" in known:
            facts.add(("region", p))
    return frozenset(facts)


READ_DIRECTLY = frozenset({"hand_empty", "holding", "upright", "on_table", "lifted", "released", "stands", "narrow",
                           "flat", "heading", "reaches", "nearer", "region", "direction", "tilted"})
"""Predicates `observed_facts` reads by rules of their own (the arms' pads, perception's uprightness, ...), and
`tilted`, the pouring pose only `pour` makes (a lying fork's axis is level too, and that is no pour); every other
predicate with constraints is read by evaluating them (`checked_facts`)."""


def checked_facts(request: Any, domain: Domain, places: list[str] = ()) -> set[Atom]:
    """The facts of every other predicate over objects and places that has constraint templates (on, inside,
    beside, left_of, over, in_region, ...): true where all its constraints hold on the perceived scene (the
    same check a sub-goal node makes), for every grounding over the visible objects and the goal's places.
    Predicates without constraints (history: poured, dropped, moved) start false."""
    import itertools
    import math

    from kintsugi.methods.agentchord.templates import fill
    from kintsugi.taskgraph.constraints import Constraint
    from kintsugi.taskgraph.features import Features
    from pydantic import TypeAdapter

    seen = {o.name: o for o in request.objects if o.visible and o.centroid is not None}
    regions = [p for p in places if p not in domain.directions]
    try:
        where = place_table(regions, domain, {o.name: o for o in request.objects}, dict(getattr(request, "regions", {})),
                            dict(getattr(request, "region_sizes", {})))
    except PlanningError:
        where = {}
    pools = {"object": list(seen), "place": [p for p in regions if p in where]}
    feats = Features(objects=seen)
    adapter = TypeAdapter(Constraint)
    out: set[Atom] = set()
    for spec in domain.predicates:
        if spec.name in READ_DIRECTLY or not spec.constraints or any(t not in pools for t in spec.params):
            continue
        for args in itertools.product(*(pools[t] for t in spec.params)):
            objs = [a for a, t in zip(args, spec.params) if t == "object"]
            if len(set(objs)) != len(objs):
                continue
            binding = {f"?{i + 1}": a for i, a in enumerate(args)}
            try:
                values = [adapter.validate_python(fill(c, binding, seen, where)).evaluate(feats)
                          for c in spec.constraints]
            except (PlanningError, ValueError):
                continue
            if values and all(v <= 0.0 for v in values if not math.isnan(v)) and not any(map(math.isnan, values)):
                out.add((spec.name, *args))
    return out


def reach_facts(request: Any, domain: Domain, known: set[str]) -> set[Atom]:
    """`reaches(arm, obj)`: the object's perceived centre within the arm's reach of its base (the robot's
    description in the domain); `nearer(arm, obj)`: no other arm's base is nearer to it. None without bases."""
    import math

    out: set[Atom] = set()
    bases = {a.name: domain.arm_bases[a.name] for a in request.arms if a.name in domain.arm_bases}
    if not bases:
        return out
    for o in request.objects:
        if not o.visible or o.centroid is None:
            continue
        d = {a: math.hypot(o.centroid[0] - b[0], o.centroid[1] - b[1]) for a, b in bases.items()}
        for a, dist in d.items():
            if "reaches" in known and dist <= domain.reach_m:
                out.add(("reaches", a, o.name))
            if "nearer" in known and dist <= min(d.values()) + 1e-9:
                out.add(("nearer", a, o.name))
    return out


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


def looks_upright(o: SeenObject) -> bool:
    """Perception's uprightness; when it could not decide (no well-defined axis), an object at least as tall
    as it is long stands upright."""
    if o.upright is not None:
        return o.upright
    if o.top_z is None or o.bottom_z is None or o.extent is None:
        return False
    return o.top_z - o.bottom_z >= UPRIGHT_HEIGHT_RATIO * max(o.extent)


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


def place_table(places: list[str], domain: Domain, seen: dict[str, SeenObject], regions: dict,
                sizes: dict | None = None) -> dict:
    """place -> region centre (x, y); ("half", place) -> its half-extents (x, y): the task statement's
    (`sizes`), else `UNSTATED_REGION_HALF_M`; ("direction", d) -> yaw for the directions."""
    from kintsugi.methods.agentchord.domain import UNSTATED_REGION_HALF_M

    out: dict = {}
    for p in places:
        if p in domain.directions:
            out[("direction", p)] = domain.directions[p]
        else:
            out[p] = place_xy(p, domain, seen, regions)
            out[("half", p)] = tuple(float(v) for v in (sizes or {}).get(p, (UNSTATED_REGION_HALF_M,) * 2))
    return out
