"""Templates over a lying object's heading and a container's footprint seen from above (part of the constraint
templates, kintsugi.taskgraph.constraints)."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field

from kintsugi.taskgraph.base import Name, NonNeg
from kintsugi.taskgraph.features import Features
from kintsugi.taskgraph.geometry import NAN, Point, head_yaw_deg, vector_feature, wrap_deg
from kintsugi.taskgraph.template import _Template


class Heading(_Template):
    """A lying object's head points along `yaw_deg` (about the vertical, from +x): |angle off| - tol (degrees).
    Judged only while no hand touches it: a hand over its middle hides the points the head rule reads
    (a held spoon's perceived head flips end to end), so a held object reads NaN, undecided."""

    kind: Literal["heading"] = "heading"
    object: Name
    yaw_deg: Annotated[float, Field(strict=True, ge=-180.0, le=180.0)]
    tol_deg: Annotated[float, Field(strict=True, gt=0.0, le=180.0)]

    def evaluate(self, f: Features) -> float:
        obj = f.objects.get(self.object)
        if obj is None or any(self.object in arm.touching for arm in f.arms.values()):
            return NAN
        yaw = head_yaw_deg(obj)
        return NAN if yaw is None else abs(wrap_deg(yaw - self.yaw_deg)) - self.tol_deg

    def refs(self):
        yield (self.object, "object", "axis_pos")
        yield (self.object, "object", "axis_neg")


class Within(_Template):
    """A point inside a container's perceived footprint, seen from above (a capsule in a tray): the larger
    excursion beyond the footprint's half length (along its principal axis) and half width (across it), plus
    `margin` (negative inside). The footprint is the container's perceived spans (`extent`: along its axis,
    then the widest across), so a rectangle's corners count, not just the circle its width would draw; a
    container with no horizontal axis (a standing cup) has a round footprint of its widest span across."""

    kind: Literal["within"] = "within"
    point: Point
    container: Name
    margin: NonNeg = 0.0

    def evaluate(self, f: Features) -> float:
        p, box = self.point.read(f), f.objects.get(self.container)
        c, ext = vector_feature(box, "centroid"), vector_feature(box, "extent")
        if p is None or c is None or ext is None:
            return NAN
        dx, dy = float(p[0]) - float(c[0]), float(p[1]) - float(c[1])
        axis = vector_feature(box, "axis")
        ux, uy = (float(axis[0]), float(axis[1])) if axis is not None else (0.0, 0.0)
        n = math.hypot(ux, uy)
        if n < LEVEL_AXIS:  # an upright axis: round
            return math.hypot(dx, dy) - float(ext[1]) / 2 + self.margin
        ux, uy = ux / n, uy / n
        along, across = abs(dx * ux + dy * uy) - float(ext[0]) / 2, abs(dy * ux - dx * uy) - float(ext[1]) / 2
        return max(along, across) + self.margin

    def refs(self):
        yield from self.point.refs()
        yield (self.container, "object", "centroid")
        yield (self.container, "object", "extent")


LEVEL_AXIS = math.sin(math.radians(60.0))
"""`Within`: an axis at least 60 degrees from vertical lies level enough to orient a footprint."""
