"""Templates of the domain filled from the observation: a node's constraints for its facts, an edge's actions
for its grounded operator (`$x(?obj)` -> the object's perceived centroid x, ...)."""

from __future__ import annotations

import re
from typing import Any

from kintsugi.methods.agentchord.angles import head_yaw_deg, wrap_deg
from kintsugi.methods.agentchord.domain import UNSTATED_REGION_HALF_M
from kintsugi.methods.agentchord.symbolic import Atom, GroundOp, PlanningError
from kintsugi.methods.agentchord.types import Domain, SeenObject

_FN = re.compile(r"^\$(x|y|z|top|hy|nhy|rx|ry|rxlo|rxhi|rylo|ryhi|yaw|mirror|thin)\(\s*(\?[A-Za-z0-9_]+)\s*(?:,\s*(-?[0-9.eE+-]+)\s*)?\)$")
_PLACE_FN = re.compile(r"([A-Za-z][A-Za-z0-9_]*)\(([A-Za-z][A-Za-z0-9_]*)\)")
_FN2 = re.compile(r"^\$(dx|dy|turn)\(\s*(\?[A-Za-z][A-Za-z0-9_]*)\s*,\s*(\?[A-Za-z][A-Za-z0-9_]*)\s*\)$")


def fill(value: Any, binding: dict[str, str], seen: dict[str, SeenObject], where: Any = None) -> Any:
    """Instantiate a template: `?p` -> its value, `$x(?obj[, d])` -> the object's perceived centroid x (y, z)
    plus d, `$hy(?obj, d)` / `$nhy` -> +/- (half its perceived y extent + d), `$rx(?place)` / `$ry` -> the
    region's centre, `$rxlo(?place, m)` / `$rxhi` / `$rylo` / `$ryhi` -> its low / high bound along x / y (its
    centre -/+ its half-extent) moved inwards by m, `$dx(?obj, ?place)` / `$dy` -> region centre minus the
    object's centroid, `$turn(?obj, ?dir)` -> the turn about the vertical bringing the object's head to the
    direction, `$top(?obj, d)` -> its perceived top's height plus d (no lower than 0), `$yaw(?dir)` -> the
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
    if fn in ("rxlo", "rxhi", "rylo", "ryhi"):
        i, sign = "xy".index(fn[1]), (-1.0 if fn.endswith("lo") else 1.0)
        centre = _where(value, arg, where or {})
        half = (where or {}).get(("half", arg)) or (UNSTATED_REGION_HALF_M,) * 2  # no size stated
        return round(centre[i] + sign * (float(half[i]) - d), 4)
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
    if fn == "top":
        if obj is None or obj.top_z is None:
            raise PlanningError(f"template {value!r}: object {arg!r} has no perceived top")
        return round(max(0.0, float(obj.top_z) + d), 4)
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
        filled = [fill(c, b, seen, where) for c in cs]
        anchor = _anchor(a[2], domain, seen) if a[0] == "in_region" and len(a) == 3 else None
        if anchor is not None:  # a region beside an object rides with it
            filled = [{**c, "anchor": anchor[0], "anchor_at": anchor[1]} if c.get("kind") == "in_region" else c
                      for c in filled]
        constraints += filled
        if spec.gripper is not None and spec.params and spec.params[0] == "arm":
            gripper[a[1]] = spec.gripper
    return constraints, gripper


def _anchor(place: str, domain: Domain, seen: dict[str, SeenObject]) -> tuple[str, list[float]] | None:
    """(object, its perceived x-y) of a place given relative to an object (`beside_left(plate)`), else None."""
    m = _PLACE_FN.fullmatch(place)
    if m is None or m.group(1) not in domain.relative_places:
        return None
    o = seen.get(m.group(2))
    if o is None or o.centroid is None:
        return None
    return m.group(2), [round(float(o.centroid[0]), 4), round(float(o.centroid[1]), 4)]


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
