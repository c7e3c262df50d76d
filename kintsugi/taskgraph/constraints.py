"""Constraint and monitor templates as data (Appendix C-G), so a model's reply never runs code.

Each template is a typed record with a `kind` and `evaluate(features) -> float`, where > 0
means violated (Eq. 3 and Eq. 11). Units: metres and degrees. A template whose inputs are
missing this step (object not perceived) reads NaN, which no monitor counts as a violation;
the `visibility` template is the one that reports tracking loss.

The same templates serve node constraints, path constraints and monitors (Eq. 14-19), plus
relational `above`, `near` and `in_region` for sub-goals.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Field, StrictBool, model_validator

from kintsugi.taskgraph.base import Name, NonNeg, Num, Vec3
from kintsugi.taskgraph.features import Features
from kintsugi.taskgraph.footprints import LEVEL_AXIS, Heading, Within  # noqa: F401 - part of this module's API
from kintsugi.taskgraph.geometry import NAN, Axes, Point, norm, top_tilt_deg, vector_feature
from kintsugi.taskgraph.template import _Template


class Drift(_Template):
    """Eq. 14, object pose drift: ||p - p_ref|| - tol. With `ref` unset, p_ref is latched at edge start."""

    kind: Literal["drift"] = "drift"
    point: Point
    tol: NonNeg
    ref: Vec3 | None = None
    axes: Axes = "xyz"

    def evaluate(self, f: Features) -> float:
        p = self.point.read(f)
        r = self.ref
        if p is None or r is None:
            return NAN
        return norm((p[0] - r[0], p[1] - r[1], p[2] - r[2]), self.axes) - self.tol

    def bind(self, f: Features) -> "Drift":
        if self.ref is not None:
            return self
        p = self.point.read(f)
        return self if p is None else self.model_copy(update={"ref": p})

    @property
    def bound(self) -> bool:
        return self.ref is not None

    def refs(self):
        yield from self.point.refs()


class Upright(_Template):
    """Eq. 15, uprightness: angle(principal axis, gravity) - tol (degrees). The axis has no sign, unless the
    object shows its top (extreme `cap`, a bottle's painted cap) or the robot tracked it (extreme
    `tracked_top`): one whose top is below its centre stands on its head and reads 180 - angle."""

    kind: Literal["upright"] = "upright"
    object: Name
    tol_deg: Annotated[float, Field(strict=True, gt=0.0, le=90.0)]
    gravity: Vec3 = (0.0, 0.0, -1.0)

    def evaluate(self, f: Features) -> float:
        obj = f.objects.get(self.object)
        return NAN if obj is None else top_tilt_deg(obj, self.gravity) - self.tol_deg

    def refs(self):
        yield (self.object, "object", "axis")


class Tilted(_Template):
    """Tilted at least `min_deg` from gravity (e.g. a bottle pouring): min_deg - angle; measured from the top
    when it is known, as for `upright` (a bottle on its head is tilted 180 degrees)."""

    kind: Literal["tilted"] = "tilted"
    object: Name
    min_deg: Annotated[float, Field(strict=True, gt=0.0, le=90.0)]
    gravity: Vec3 = (0.0, 0.0, -1.0)

    def evaluate(self, f: Features) -> float:
        obj = f.objects.get(self.object)
        return NAN if obj is None else self.min_deg - top_tilt_deg(obj, self.gravity)

    def refs(self):
        yield (self.object, "object", "axis")


class NotGrasped(_Template):
    """Eq. 16, not fully grasped: the fingers closed past `min_opening` (m), so nothing is between them."""

    kind: Literal["not_grasped"] = "not_grasped"
    arm: Name
    min_opening: NonNeg

    def evaluate(self, f: Features) -> float:
        arm = f.arms.get(self.arm)
        return NAN if arm is None else self.min_opening - float(arm.opening)

    def refs(self):
        yield (self.arm, "arm", "opening")


class Detached(_Template):
    """Eq. 17, slipped grasp: ||c_obj - p_eef|| - tol."""

    kind: Literal["detached"] = "detached"
    arm: Name
    object: Name
    tol: NonNeg

    def evaluate(self, f: Features) -> float:
        arm = f.arms.get(self.arm)
        obj = f.objects.get(self.object)
        if arm is None or obj is None:
            return NAN
        c, e = obj.centroid, arm.eef
        if c is None:
            return NAN
        d = (float(c[0]) - float(e[0]), float(c[1]) - float(e[1]), float(c[2]) - float(e[2]))
        return norm(d, "xyz") - self.tol

    def refs(self):
        yield (self.arm, "arm", "eef")
        yield (self.object, "object", "centroid")


class Visibility(_Template):
    """Eq. 18, tracking loss: n_min - n_points (an object absent from the features has zero points)."""

    kind: Literal["visibility"] = "visibility"
    object: Name
    n_min: Annotated[int, Field(strict=True, ge=1, le=10_000_000)]

    def evaluate(self, f: Features) -> float:
        obj = f.objects.get(self.object)
        return float(self.n_min - (0 if obj is None else int(obj.n_points)))

    def refs(self):
        yield (self.object, "object", "n_points")


class _Separation(_Template):
    """||(a - b) restricted to `axes`|| - tol."""

    a: Point
    b: Point
    tol: NonNeg

    def evaluate(self, f: Features) -> float:
        pa, pb = self.a.read(f), self.b.read(f)
        if pa is None or pb is None:
            return NAN
        return norm((pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]), self.axes) - self.tol

    def refs(self):
        yield from self.a.refs()
        yield from self.b.refs()


class Misaligned(_Separation):
    """Eq. 19, relational misalignment: lateral (default xy) offset between two entities - tol."""

    kind: Literal["misaligned"] = "misaligned"
    axes: Axes = "xy"


class Near(_Separation):
    """`a` within `tol` of `b` (full 3-D distance by default)."""

    kind: Literal["near"] = "near"
    axes: Axes = "xyz"


class Above(_Template):
    """`a` at least `min_gap` above `b` along z: (b_z + min_gap) - a_z."""

    kind: Literal["above"] = "above"
    a: Point
    b: Point
    min_gap: Num = 0.0

    def evaluate(self, f: Features) -> float:
        pa, pb = self.a.read(f), self.b.read(f)
        if pa is None or pb is None:
            return NAN
        return pb[2] + self.min_gap - pa[2]

    def refs(self):
        yield from self.a.refs()
        yield from self.b.refs()


class InRegion(_Template):
    """Point inside the box [lo, hi]: the largest per-axis excursion outside it (negative inside).

    A region placed beside an object (`beside_left(plate)`) names it as its `anchor`, with `anchor_at`, the
    anchor's centroid (x, y) where the box was placed: the box rides with the anchor, shifted in x-y by how far
    its perceived centroid has moved since (NaN while the anchor is not perceived)."""

    kind: Literal["in_region"] = "in_region"
    point: Point
    lo: Vec3
    hi: Vec3
    anchor: Name | None = None
    anchor_at: tuple[Num, Num] | None = None

    @model_validator(mode="after")
    def _ordered(self) -> "InRegion":
        if any(l > h for l, h in zip(self.lo, self.hi)):
            raise ValueError(f"region lo {self.lo} exceeds hi {self.hi} on some axis")
        if (self.anchor is None) != (self.anchor_at is None):
            raise ValueError("give `anchor` and `anchor_at` together (the object the region rides with, and where "
                             "it was when the region was placed)")
        return self

    def shift(self, f: Features) -> tuple[float, float] | None:
        """How far (x, y) the anchor has moved since the region was placed; (0, 0) without one, None unseen."""
        if self.anchor is None or self.anchor_at is None:
            return (0.0, 0.0)
        c = Point(entity=self.anchor).read(f)
        return None if c is None else (c[0] - self.anchor_at[0], c[1] - self.anchor_at[1])

    def evaluate(self, f: Features) -> float:
        p, d = self.point.read(f), self.shift(f)
        if p is None or d is None:
            return NAN
        lo, hi = self.lo, self.hi
        return max(lo[0] + d[0] - p[0], p[0] - hi[0] - d[0], lo[1] + d[1] - p[1], p[1] - hi[1] - d[1],
                   lo[2] - p[2], p[2] - hi[2])

    def refs(self):
        yield from self.point.refs()
        if self.anchor is not None:
            yield (self.anchor, "point", None)


class Offset(_Template):
    """`a` relative to `b` inside the box [lo, hi] (world axes, metres): the largest per-axis excursion outside it
    (negative inside). Relations between objects: `left_of` (a's centre 6.5-27.5 cm to b's +y side), a stacked
    object's bottom at its support's top (z within a few millimetres)."""

    kind: Literal["offset"] = "offset"
    a: Point
    b: Point
    lo: Vec3
    hi: Vec3

    @model_validator(mode="after")
    def _ordered(self) -> "Offset":
        if any(l > h for l, h in zip(self.lo, self.hi)):
            raise ValueError(f"offset lo {self.lo} exceeds hi {self.hi} on some axis")
        return self

    def evaluate(self, f: Features) -> float:
        pa, pb = self.a.read(f), self.b.read(f)
        if pa is None or pb is None:
            return NAN
        d = [pa[i] - pb[i] for i in range(3)]
        return max(max(self.lo[i] - d[i], d[i] - self.hi[i]) for i in range(3))

    def refs(self):
        yield from self.a.refs()
        yield from self.b.refs()


class Spacing(_Template):
    """The distance between `a` and `b` (over `axes`, default horizontal) within [min_m, max_m]: the larger
    excursion outside that band (negative inside). `beside`: next to, either side, not on or touching."""

    kind: Literal["spacing"] = "spacing"
    a: Point
    b: Point
    min_m: NonNeg = 0.0
    max_m: NonNeg
    axes: Axes = "xy"

    @model_validator(mode="after")
    def _ordered(self) -> "Spacing":
        if self.min_m > self.max_m:
            raise ValueError(f"spacing min_m {self.min_m} exceeds max_m {self.max_m}")
        return self

    def evaluate(self, f: Features) -> float:
        pa, pb = self.a.read(f), self.b.read(f)
        if pa is None or pb is None:
            return NAN
        d = norm((pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]), self.axes)
        return max(self.min_m - d, d - self.max_m)

    def refs(self):
        yield from self.a.refs()
        yield from self.b.refs()


class Touching(_Template):
    """The arm's fingers touch `object` (or, with expect=false, do not): -1 satisfied, +1 violated."""

    kind: Literal["touching"] = "touching"
    arm: Name
    object: Name
    expect: StrictBool = True
    while_closed: StrictBool = False
    """Judge only while the gripper is commanded closed: an edge that opens the hand on purpose (a place)
    is watched for a drop up to its release, and the release itself is no failure."""

    def evaluate(self, f: Features) -> float:
        arm = f.arms.get(self.arm)
        if arm is None:
            return NAN
        if self.while_closed and not arm.closed:
            return -1.0
        return -1.0 if (self.object in arm.touching) == self.expect else 1.0

    def refs(self):
        yield (self.arm, "arm", "touching")
        yield (self.object, "object", None)


TEMPLATES: tuple[type[_Template], ...] = (
    Drift, Upright, Tilted, NotGrasped, Detached, Visibility, Misaligned, Near, Above, InRegion, Touching, Heading,
    Within, Offset, Spacing,
)

Constraint = Annotated[
    Union[Drift, Upright, Tilted, NotGrasped, Detached, Visibility, Misaligned, Near, Above, InRegion, Touching,
          Heading, Within, Offset, Spacing],
    Field(discriminator="kind"),
]
"""Any template, chosen by its `kind` field in JSON."""
