"""Reading the instruction and the scene: which object, which skill words, which fixture and face.

The words of the instruction are matched against the objects' names and labels; the geometry (sizes, poses,
fixtures) decides the rest. Nothing here writes cost code.
"""

from __future__ import annotations

import math
import re

from kintsugi.methods.coral.types import FormulationRequest, ObjectState, RegionSpec


class NotUnderstood(ValueError):
    """The instruction names no skill the library has, or no object the scene holds."""


def words(text: str) -> list[str]:
    return [w.strip(".") for w in re.findall(r"[a-z0-9.]+", text.lower()) if w.strip(".")]


def target_object(req: FormulationRequest) -> ObjectState:
    """The object the instruction names first (its label or name; plural forms count)."""
    text = " " + " ".join(words(req.task)) + " "
    best: tuple[int, ObjectState] | None = None
    for o in req.objects:
        for w in {o.name.lower(), *words(o.label)}:
            w = re.sub(r"\d+$", "", w)
            for form in (w, w + "s", w + "es"):
                i = text.find(f" {form} ")
                if i >= 0 and (best is None or i < best[0]):
                    best = (i, o)
    if best is None:
        raise NotUnderstood(f"the instruction names none of the objects: {', '.join(o.label for o in req.objects)}")
    return best[1]


def force_n(text: str) -> float | None:
    m = re.search(r"(\d+(?:\.\d+)?)\s*(?:n|newtons?)\b", text.lower())
    return float(m.group(1)) if m else None


def duration_s(text: str) -> float | None:
    """'for 2 seconds', 'for 1.5 s': how long the instruction asks a press to last."""
    m = re.search(r"for\s+(\d+(?:\.\d+)?)\s*(?:s|secs?|seconds?)\b", text.lower())
    return float(m.group(1)) if m else None


def tall(o: ObjectState) -> bool:
    """Stands on a small face: taller than it is wide, and upright."""
    return o.size_m[2] > max(o.size_m[0], o.size_m[1]) and o.upright_deg < 30


def toward(o: ObjectState, req: FormulationRequest) -> tuple[str | None, int, float]:
    """The fixture the object goes to (nearest), the world axis and the sign of the push toward it."""
    if req.fixtures:
        f = min(req.fixtures, key=lambda f: math.dist(_centre(f), o.pos_m))
        c = _centre(f)
        dx, dy = c[0] - o.pos_m[0], c[1] - o.pos_m[1]
    else:  # away from the robot's home: the far side of the object is free
        f, (dx, dy) = None, (o.pos_m[0] - req.robot.home_m[0], o.pos_m[1] - req.robot.home_m[1])
    axis = 0 if abs(dx) >= abs(dy) else 1
    sign = 1.0 if (dx if axis == 0 else dy) >= 0 else -1.0
    return (f.name if f else None), axis, sign


def _centre(f) -> tuple[float, float, float]:  # noqa: ANN001 - a FixtureView
    return tuple((a + b) / 2 for a, b in zip(f.lo_m, f.hi_m))  # type: ignore[return-value]


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
