"""Reading points, distances and angles from the features: what the constraint templates compare.

A `Point` is an entity's vector feature (a centroid, an extreme such as `top`, a fraction of the way along an
object's axis, or an arm's end effector) plus an offset; the angle helpers read tilt from gravity (sign-free,
or from the object's known top) and a lying object's heading. Anything missing this step reads None or NaN.
"""

from __future__ import annotations

import math
from typing import Annotated, Iterator, Literal, Mapping

from pydantic import Field, model_validator

from kintsugi.taskgraph.base import GraphModel, Name, Vec3
from kintsugi.taskgraph.features import Features

Axes = Literal["xyz", "xy", "xz", "yz", "x", "y", "z"]
_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}
NAN = math.nan

RefRole = Literal["object", "arm", "point"]
"""What a referenced entity must be: an object, an arm, or either (a point read from it)."""


def vector_feature(obj: object, name: str):
    """A 3-vector feature by name: an attribute, or an entry of the object's `extremes` mapping.

    None when the object does not have it this step (e.g. not visible).
    """
    v = getattr(obj, name, None)
    if v is None:
        extremes = getattr(obj, "extremes", None)
        if isinstance(extremes, Mapping):
            v = extremes.get(name)
    return v


def centre(obj: object):
    """Where the object is: for an unfitted cloud (`fit == "raw"`, whose mean leans towards a wide end) the middle
    of its perceived axis ends, else its centroid (a fitted shape's centre holds where hands hide part of it)."""
    a, b = vector_feature(obj, "axis_neg"), vector_feature(obj, "axis_pos")
    if getattr(obj, "fit", None) != "raw" or a is None or b is None:
        return vector_feature(obj, "centroid")
    return tuple((float(a[i]) + float(b[i])) / 2.0 for i in range(3))


class Point(GraphModel):
    """A 3-D point read from the features, plus a world-frame offset.

    Object: a vector feature (default `centroid`; extremes such as `top` by name; `centre`: for an
    unfitted cloud the middle of its perceived axis ends, else its centroid: an unfitted cloud's
    mean drifts by centimetres towards a wide end, a fork's head), or with `along` the point that
    fraction of the way from `axis_neg` (0) to `axis_pos` (1), e.g. 0.75 up a bottle. Arm: its end
    effector (`eef`, the only arm point).
    """

    entity: Name
    feature: Name | None = None
    along: Annotated[float, Field(strict=True, ge=0.0, le=1.0)] | None = None
    offset: Vec3 = (0.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _one_way(self) -> "Point":
        if self.along is not None and self.feature is not None:
            raise ValueError("give either `feature` or `along`, not both")
        return self

    def read(self, f: Features) -> tuple[float, float, float] | None:
        arm = f.arms.get(self.entity)
        if arm is not None:
            v = arm.eef
        else:
            obj = f.objects.get(self.entity)
            if obj is None:
                return None
            if self.feature == "centre":
                v = centre(obj)
            elif self.along is None:
                v = vector_feature(obj, self.feature or "centroid")
            else:
                a, b = vector_feature(obj, "axis_neg"), vector_feature(obj, "axis_pos")
                if a is None or b is None:
                    return None
                t = self.along
                v = tuple(float(a[i]) + t * (float(b[i]) - float(a[i])) for i in range(3))
            if v is None:
                return None
        ox, oy, oz = self.offset
        return (float(v[0]) + ox, float(v[1]) + oy, float(v[2]) + oz)

    def refs(self) -> Iterator[tuple[str, RefRole, str | None]]:
        if self.along is None:
            yield (self.entity, "point", self.feature)
        else:
            yield (self.entity, "object", "axis_neg")
            yield (self.entity, "object", "axis_pos")


def norm(d: tuple[float, float, float], axes: str) -> float:
    if axes == "xyz":
        return math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    return math.sqrt(sum(d[_AXIS_INDEX[a]] ** 2 for a in axes))


def tilt_deg(axis, gravity: Vec3) -> float:
    """Angle between a sign-free principal axis and gravity, in [0, 90] degrees; NaN without an axis."""
    if axis is None:
        return NAN
    ax, ay, az = float(axis[0]), float(axis[1]), float(axis[2])
    gx, gy, gz = gravity
    n = math.sqrt(ax * ax + ay * ay + az * az) * math.sqrt(gx * gx + gy * gy + gz * gz)
    if not n > 0.0:
        return NAN
    return math.degrees(math.acos(min(1.0, abs(ax * gx + ay * gy + az * gz) / n)))


def top_tilt_deg(obj: object, gravity: Vec3) -> float:
    """The object's tilt from standing: sign-free (0-90 degrees), or from its top (0-180) when the top is known,
    by a seen cap, a container's seen opening or the robot's tracked top, in that order (what the cameras see
    of an end beats the robot's inference from its encoders: a lying cup's top is a guess that a stand-up can
    get wrong); one whose top is below its centre reads 180 - the axis's tilt."""
    tilt = tilt_deg(getattr(obj, "axis", None), gravity)
    top, centre = vector_feature(obj, "cap"), vector_feature(obj, "centroid")
    if top is None:  # a container's open end is its top
        top = vector_feature(obj, "opening")
    if top is None:
        top = vector_feature(obj, "tracked_top")
    if top is not None and centre is not None and dot(top, gravity) > dot(centre, gravity):
        tilt = 180.0 - tilt
    return tilt


def dot(a, b) -> float:
    return float(a[0]) * float(b[0]) + float(a[1]) * float(b[1]) + float(a[2]) * float(b[2])


def head_yaw_deg(obj: object) -> float | None:
    """Yaw (degrees from +x about the vertical) of a long lying object's head: its wide head pulls the point
    cloud's centroid towards it, so the axis end nearer the centroid (in x-y) is the head. None without ends."""
    c, a, b = (vector_feature(obj, k) for k in ("centroid", "axis_pos", "axis_neg"))
    if c is None or a is None or b is None:
        return None
    da, db = math.hypot(a[0] - c[0], a[1] - c[1]), math.hypot(b[0] - c[0], b[1] - c[1])
    near, far = (a, b) if da <= db else (b, a)
    dx, dy = float(near[0]) - float(far[0]), float(near[1]) - float(far[1])
    if math.hypot(dx, dy) < 1e-6:
        return None
    return math.degrees(math.atan2(dy, dx))


def wrap_deg(d: float) -> float:
    return (d + 180.0) % 360.0 - 180.0
