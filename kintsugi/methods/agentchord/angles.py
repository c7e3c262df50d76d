"""Angles read off a perceived object: a lying object's head direction, and wrapping to [-180, 180)."""

from __future__ import annotations

from kintsugi.methods.agentchord.types import SeenObject


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
