"""The goal check refuses a verdict that rests on regions an outside hand has moved since the plan was made.

A region given relative to an object ("beside the plate") is placed where that object was seen when the graph was
compiled. When the object has since been slid (by something other than this robot's hands) the region's checks
still read its old place, and a fork set beside the plate's old place would pass them. Until the checks are
re-aimed at run time, the verdict is no success: an object that no hand took up, seen more than `MOVED_M` from
where it was first seen, and within `NEAR_M` of a goal region's centre, makes that region stale.
"""

from __future__ import annotations

from typing import Any

import numpy as np

MOVED_M = 0.03
NEAR_M = 0.3
REGION_SPAN_M = 1.0
"""A box narrower than this (x or y) is a region of the table, not `on_table`'s whole-table box."""


def stale_regions(goal: Any, seen: dict[str, tuple[float, float]], taken: dict[str, Any],
                  now: dict[str, Any]) -> list[str]:
    """`moved object -> region centre` notes for every goal region near an object that moved untouched."""
    centres = []
    for c in goal.constraints:
        if c.kind == "in_region" and min(h - lo for lo, h in zip(c.lo[:2], c.hi[:2])) < REGION_SPAN_M:
            centres.append((np.array([(c.lo[0] + c.hi[0]) / 2, (c.lo[1] + c.hi[1]) / 2]),
                            {e for e, role, _ in c.refs() if role != "arm"}))
    out = []
    for name, first in seen.items():
        f = now.get(name)
        if name in taken or f is None or getattr(f, "centroid", None) is None:
            continue
        moved = float(np.hypot(f.centroid[0] - first[0], f.centroid[1] - first[1]))
        if moved <= MOVED_M:
            continue
        for centre, inside in centres:
            if name not in inside and float(np.linalg.norm(centre - np.asarray(first, float))) <= NEAR_M:
                out.append(f"{name} moved {moved * 100:.1f} cm since the plan; the region at "
                           f"({centre[0]:.3f}, {centre[1]:.3f}) was placed by where it was")
    return out
