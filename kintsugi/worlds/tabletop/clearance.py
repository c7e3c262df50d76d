"""How close a point comes to a perceived object: each object taken as a vertical capsule over the footprint
of its axis ends, with half its perceived width as radius, between its perceived bottom and top.

Only perceived geometry is read (the robot's planner and AgentChord's edge synthesis both use it). A capsule is
coarse, but it is what a depth cloud gives without a mesh, and it errs on the side of more room.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def across(f: Any) -> float:
    """Half the perceived object's width across its axis."""
    if f.extent is None:
        return 0.03
    return float(max(f.extent[1], f.extent[2])) / 2.0


def gap(p: np.ndarray, z_lo: float, z_hi: float, o: Any) -> float:
    """Horizontal clearance from point p (swept from z_lo to z_hi) to a perceived object; +inf when their
    heights do not meet."""
    top = o.extremes.get("top") if o.extremes else None
    bottom = o.extremes.get("bottom") if o.extremes else None
    if top is not None and bottom is not None and (z_hi < bottom[2] or z_lo > top[2]):
        return float("inf")
    ends = [o.extremes.get(k) for k in ("axis_pos", "axis_neg")] if o.extremes else [None, None]
    a = np.array(ends[0] if ends[0] is not None else o.centroid, dtype=float)[:2]
    b = np.array(ends[1] if ends[1] is not None else o.centroid, dtype=float)[:2]
    d = b - a
    t = 0.0 if float(d @ d) < 1e-12 else float(np.clip((p[:2] - a) @ d / (d @ d), 0.0, 1.0))
    return float(np.linalg.norm(p[:2] - (a + t * d))) - across(o)


def top_z(o: Any) -> float:
    """The perceived object's highest point (its centroid's height when no top was perceived)."""
    top = o.extremes.get("top") if o.extremes else None
    return float(top[2] if top is not None else o.centroid[2])
