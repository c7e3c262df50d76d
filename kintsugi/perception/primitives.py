"""Known shapes of objects (cylinder, box, sphere) and a shape placed in the world by a fit.

`Primitive` is what a robot's object catalogue states about an object's shape; `Fit` is that shape placed
in the world (centre, frame, size) with the quality of the fit (kintsugi.perception.fitting fits it to a
point cloud); `surface_samples` gives fixed points on a fitted surface, for checks against the cameras.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import PositiveFloat, model_validator

from kintsugi.core.config import StrictModel

DEADZONE = float(np.sin(np.radians(5.0)))  # a direction within 5 deg of a face/axis counts as along it


class Primitive(StrictModel):
    """The known shape of an object, as a robot's object catalogue states it (metres, MuJoCo size conventions).

    cylinder: `radius`, optional `half_length` (half its height along the axis);
    box: `half_extents`; sphere: `radius`; none: no known shape (raw features only).
    `wall`: the object is a container open at one end (a cup: the cylinder's +axis end;
    a tray: the box's +z face) with walls and floor this thick, so that the points a
    camera sees inside it lie on the shape too.
    """

    kind: Literal["cylinder", "box", "sphere", "none"] = "none"
    radius: PositiveFloat | None = None
    half_length: PositiveFloat | None = None
    half_extents: tuple[PositiveFloat, PositiveFloat, PositiveFloat] | None = None
    wall: PositiveFloat | None = None

    @model_validator(mode="after")
    def _fields_match_kind(self) -> Primitive:
        need = {"cylinder": {"radius"}, "box": {"half_extents"}, "sphere": {"radius"}, "none": set()}[self.kind]
        allowed = need | ({"half_length", "wall"} if self.kind == "cylinder" else set())
        allowed |= {"wall"} if self.kind == "box" else set()
        given = {f for f in ("radius", "half_length", "half_extents", "wall") if getattr(self, f) is not None}
        if need - given:
            raise ValueError(f"a {self.kind} primitive needs {', '.join(sorted(need - given))}")
        if given - allowed:
            raise ValueError(f"a {self.kind} primitive takes no {', '.join(sorted(given - allowed))}")
        if self.wall is not None:
            if self.kind == "cylinder" and self.half_length is None:
                raise ValueError("a cylinder container (wall) needs half_length")
            inner = (self.radius, 2 * self.half_length) if self.kind == "cylinder" else (
                min(self.half_extents[:2]), 2 * self.half_extents[2])  # type: ignore[index]
            if self.wall >= min(inner):
                raise ValueError(f"wall {self.wall} leaves no cavity inside the {self.kind}")
        return self

    @classmethod
    def cylinder(cls, radius: float, half_length: float | None = None, wall: float | None = None) -> Primitive:
        return cls(kind="cylinder", radius=radius, half_length=half_length, wall=wall)

    @classmethod
    def box(cls, hx: float, hy: float, hz: float, wall: float | None = None) -> Primitive:
        return cls(kind="box", half_extents=(hx, hy, hz), wall=wall)

    @classmethod
    def sphere(cls, radius: float) -> Primitive:
        return cls(kind="sphere", radius=radius)


@dataclass(frozen=True)
class Fit:
    """A primitive placed in the world: centre, local frame (columns), residuals of the fit."""

    kind: Literal["cylinder", "box", "sphere"]
    centre: np.ndarray  # (3,)
    frame: np.ndarray  # (3, 3); cylinder axis = column 2
    size: np.ndarray  # cylinder (r, h, 0); box half extents; sphere (r, 0, 0)
    rms: float  # RMS of the inlier residuals, metres
    inliers: float  # fraction of points within the inlier tolerance of the surface
    wall: float = 0.0  # > 0: a container open at its local +z end

    @property
    def opening(self) -> np.ndarray | None:
        """Centre of a container's open end (None for solids)."""
        if self.wall <= 0.0 or self.kind == "sphere":
            return None
        return self.centre + self.frame[:, 2] * (self.size[1] if self.kind == "cylinder" else self.size[2])

    @property
    def axis(self) -> np.ndarray | None:
        """Cylinder axis, a box's longest axis, or None for a sphere (no axis)."""
        if self.kind == "cylinder":
            return self.frame[:, 2]
        if self.kind == "box":
            return self.frame[:, int(np.argmax(self.size))]
        return None

    @property
    def bound_radius(self) -> float:
        """Distance from the centre to the farthest point of the primitive."""
        if self.kind == "cylinder":
            return float(np.hypot(self.size[0], self.size[1]))
        return float(np.linalg.norm(self.size))

    @property
    def half_length(self) -> float:
        """Half the primitive's length along `axis`."""
        return float(self.size[1] if self.kind == "cylinder" else np.max(self.size))

    def support(self, direction: np.ndarray) -> np.ndarray:
        """Centre of the primitive's extreme face/edge/point in `direction` (e.g. +z: the top)."""
        d = self.frame.T @ (np.asarray(direction, float) / np.linalg.norm(direction))
        if self.kind == "sphere":
            local = self.size[0] * d
        elif self.kind == "box":
            local = np.where(np.abs(d) > DEADZONE, np.sign(d), 0.0) * self.size
        else:
            radial = np.hypot(d[0], d[1])
            local = np.zeros(3)
            if radial > DEADZONE:
                local[:2] = self.size[0] * d[:2] / radial
            if abs(d[2]) > DEADZONE:
                local[2] = np.sign(d[2]) * self.size[1]
        return self.centre + self.frame @ local


def surface_samples(fit: Fit, inset: float) -> np.ndarray:
    """A fixed set of points on the fitted primitive's surface, moved `inset` inwards (world frame)."""
    if fit.kind == "sphere":
        k = np.arange(120) + 0.5
        z = 1 - 2 * k / 120
        phi = np.pi * (1 + 5**0.5) * k
        rho = np.sqrt(1 - z * z)
        local = (fit.size[0] - inset) * np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    elif fit.kind == "cylinder":
        # A container's wall may be thinner than the inset: inside it, the camera rightly sees the cavity.
        r = max(fit.size[0] - (min(inset, fit.wall / 2) if fit.wall else inset), 0.0)
        h = max(fit.size[1] - inset, 0.0)
        zb = -fit.size[1] + (min(inset, fit.wall / 2) if fit.wall else inset)
        phi = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        side = [np.column_stack([r * np.cos(phi), r * np.sin(phi), np.full(24, t)]) for t in np.linspace(-h, h, 7)]
        ends = (zb,) if fit.wall else (-h, h)  # a container's open end is no surface
        caps = [np.column_stack([f * r * np.cos(phi), f * r * np.sin(phi), np.full(24, z)]) for f in (0.5, 1.0) for z in ends]
        local = np.vstack(side + caps + [[[0.0, 0.0, z] for z in ends]])
    else:
        he = np.maximum(fit.size - (min(inset, fit.wall / 2) if fit.wall else inset), 0.0)
        g = np.linspace(-1, 1, 5)
        u, v = (a.ravel() for a in np.meshgrid(g, g))
        faces = []
        for k in range(3):
            i, j = [m for m in range(3) if m != k]
            for sign in (-1.0, 1.0):
                if fit.wall and k == 2 and sign > 0:
                    continue  # a tray's open top
                face = np.zeros((25, 3))
                face[:, i], face[:, j], face[:, k] = u * he[i], v * he[j], sign * he[k]
                faces.append(face)
        local = np.vstack(faces)
    return fit.centre + local @ fit.frame.T
