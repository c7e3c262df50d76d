"""The plan's parts: primitives, segments, the plan, and the geometry a plan is worked out with.

A primitive prints as `name object key=value ...` (the instruction suite lists plans this way).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from kintsugi.methods.coral.types import FormulationRequest, ObjectState

DEFAULT_PUSH_M = 0.10
"""A push given a direction but no distance goes this far (the plan says so in its notes)."""
DEFAULT_PRESS_S = 2.0
DEFAULT_HOLD_S = 1.0
MAX_PUSH_M = 0.40
MIN_OVERHANG_LENGTH_M = 0.15
"""An object pushed out over the table edge must be at least this long: it sticks out far enough to be pinched
from below (beyond the fingers' width) and still rests mostly on the table."""
AXES = {"forward": (0, 1.0), "back": (0, -1.0), "left": (1, 1.0), "right": (1, -1.0)}
"""Robot-frame directions as (world axis, sign): the robot faces +x, its left is +y."""
ROUND_SHAPES = ("cylinder", "sphere", "ball", "puck", "can", "capsule")
FINGER_MARGIN_M = 0.015
"""How much narrower than the open gripper a side must be to be pinched across."""


@dataclass
class Primitive:
    name: str
    obj: str | None = None
    params: dict[str, object] = field(default_factory=dict)

    def __str__(self) -> str:
        args = " ".join(f"{k}={_fmt(v)}" for k, v in self.params.items())
        return " ".join(x for x in (self.name, self.obj or "", args) if x)


@dataclass
class Segment:
    """Primitives one cost builder writes together (`builder` names it in costlib)."""

    builder: str
    obj: str | None
    prims: list[Primitive]
    args: dict[str, object] = field(default_factory=dict)


@dataclass
class CostPlan:
    steps: list[Step]
    segments: list[Segment]
    notes: list[str] = field(default_factory=list)

    @property
    def primitives(self) -> list[str]:
        return [str(p) for s in self.segments for p in s.prims]


def _fmt(v: object) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def fits(o: ObjectState, max_opening: float) -> bool:
    return min(o.size_m[0], o.size_m[1]) < max_opening - FINGER_MARGIN_M


def tall(o: ObjectState) -> bool:
    return o.size_m[2] > max(o.size_m[0], o.size_m[1]) and o.upright_deg < 30


def _centre(f) -> tuple[float, float]:  # noqa: ANN001 - a FixtureView
    return (f.lo_m[0] + f.hi_m[0]) / 2, (f.lo_m[1] + f.hi_m[1]) / 2


def _axis(dx: float, dy: float) -> tuple[int, float]:
    axis = 0 if abs(dx) >= abs(dy) else 1
    return axis, (1.0 if (dx if axis == 0 else dy) >= 0 else -1.0)


def _dirname(axis: int, sign: float) -> str:
    return {(0, 1.0): "+x", (0, -1.0): "-x", (1, 1.0): "+y", (1, -1.0): "-y"}[(axis, sign)]


def point_xy(o: ObjectState, p: tuple, req: FormulationRequest) -> tuple[float, float]:
    """A leg's point (see costlib.slide) in world x, y as perceived at formulation."""
    if p[0] == "first":
        return o.pos_m[0] + p[1], o.pos_m[1] + p[2]
    if p[0] == "marker":
        m = next(x for x in req.markers if x.name == p[1])
        return m.x_m, m.y_m
    return p[1], p[2]


def around(o: ObjectState, origin: tuple, goal: tuple, req: FormulationRequest, avoid: set[str],
           notes: list[str]) -> list[tuple[tuple, tuple]]:
    """The legs of a push from origin to goal: one, or two by a way point beside a fixture to avoid that
    stands in the way (on the side away from the line's offset, far enough for the object and the fingers)."""
    (ax, ay), (gx, gy) = point_xy(o, origin, req), point_xy(o, goal, req)
    length = math.hypot(gx - ax, gy - ay)
    if length < 1e-6 or not avoid:
        return [(origin, goal)]
    ux, uy = (gx - ax) / length, (gy - ay) / length
    nx, ny = -uy, ux
    radius = math.hypot(o.size_m[0], o.size_m[1]) / 2
    for name in sorted(avoid):
        f = next(x for x in req.fixtures if x.name == name)
        (cx, cy), hx, hy = _centre(f), (f.hi_m[0] - f.lo_m[0]) / 2, (f.hi_m[1] - f.lo_m[1]) / 2
        along = (cx - ax) * ux + (cy - ay) * uy
        side = (cx - ax) * nx + (cy - ay) * ny
        reach = abs(nx) * hx + abs(ny) * hy + radius + 0.01
        if not 0.0 < along < length or abs(side) > reach:
            continue
        off = reach + 0.03
        sgn = -1.0 if side > 0 else 1.0
        if abs(side) < 1e-3:  # straight ahead: the side nearer the middle of the table
            sgn = 1.0 if (cy + ny * off) ** 2 <= (cy - ny * off) ** 2 else -1.0
        wp = ("point", round(cx + sgn * nx * off, 4), round(cy + sgn * ny * off, 4))
        notes.append(f"{name} stands in the way: the push goes by {wp[1]:.3f}, {wp[2]:.3f}")
        return [(origin, wp), (wp, goal)]
    return [(origin, goal)]
