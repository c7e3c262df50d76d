"""Where on an object the fingers push: the face turned away from the push, as a contact region.

The instruction is read in `kintsugi.methods.coral.language` and planned in `kintsugi.methods.coral.plan`;
nothing here reads words.
"""

from __future__ import annotations

import math

from kintsugi.methods.coral.types import ObjectState, RegionSpec


def back_face(o: ObjectState, axis: int, sign: float, height_frac: float | None, z_m: float, k: dict[str, float]
              ) -> RegionSpec:
    """The face turned away from the push, in the object's frame (its yaw is small): where the closed fingers push.
    `height_frac` of the object's height, or `z_m` above its bottom."""
    half = [s / 2 for s in o.size_m]
    yaw = math.radians(o.yaw_deg)
    # push direction in the object's frame, snapped to its nearest principal axis
    wx, wy = (sign, 0.0) if axis == 0 else (0.0, sign)
    lx, ly = math.cos(yaw) * wx + math.sin(yaw) * wy, -math.sin(yaw) * wx + math.cos(yaw) * wy
    ax, s = (0, math.copysign(1.0, lx)) if abs(lx) >= abs(ly) else (1, math.copysign(1.0, ly))
    z = -half[2] + (height_frac * 2 * half[2] if height_frac is not None else z_m)
    centre = [0.0, 0.0, z]
    normal = [0.0, 0.0, 0.0]
    centre[ax], normal[ax] = -s * half[ax], -s
    return RegionSpec(object=o.name, center=tuple(centre), normal=tuple(normal),  # type: ignore[arg-type]
                      radius=0.01 if height_frac is not None else 0.008, standoff=k["paddle_m"],
                      drop=0.0 if height_frac is not None else 0.006)
