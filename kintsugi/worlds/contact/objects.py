"""What a contact scene is made of, split the way the paper splits knowledge.

- `Geometry`: an object's shape, as its known 3D model gives it (CoRAL gets object meshes), with
  what a person would call it (`label`: "wooden board") and what it looks made of (`material`).
  Those two are what a user and a camera can tell; they never carry the mass or friction.
- `Physics`: mass and friction. In the evaluation world these are the TRUTH; in the
  planning world the same type holds BELIEFS (`Beliefs`), set from a prior or from
  system identification. Nothing in a method may build a `Physics` from the evaluation
  world, except the oracle baselines, through `oracle_beliefs` (see beliefs.py).
- `Placement`: where an object starts on the table.

Shapes: every part of an object is a box, a cylinder, a sphere or a capsule (`SHAPES`). A part's
`half` is always the half-extent of its bounding box in the object's frame, so a part's footprint,
resting height and size read the same for every shape; its volume, lowest point and bounds under
any rotation follow the shape itself (`support`: the shape's extent along a direction).
"""

from __future__ import annotations

import itertools
import math
from typing import Literal

import numpy as np
from pydantic import model_validator

from kintsugi.core.config import StrictModel

Vec3 = tuple[float, float, float]
RGBA = tuple[float, float, float, float]

SHAPES: dict[str, str] = {
    "box": "a box: half = its half-extents (x, y, z)",
    "cylinder": "a cylinder along `axis`: half = radius across the axis, half-length along it",
    "sphere": "a sphere: half = its radius three times",
    "capsule": "a capsule along `axis`: half = radius across it, half-length including the round caps along it",
}
"""The shapes a part may have, each with how its `half` reads."""
COLOURS: dict[str, RGBA] = {
    "red": (0.85, 0.2, 0.15, 1.0), "green": (0.25, 0.7, 0.3, 1.0), "blue": (0.2, 0.35, 0.85, 1.0),
    "yellow": (0.9, 0.8, 0.2, 1.0), "orange": (0.95, 0.55, 0.15, 1.0), "purple": (0.55, 0.3, 0.75, 1.0),
    "white": (0.92, 0.92, 0.9, 1.0), "black": (0.12, 0.12, 0.12, 1.0), "grey": (0.6, 0.6, 0.6, 1.0),
    "brown": (0.55, 0.38, 0.22, 1.0)}
"""Colour names an object may be given (its `colour`, which sets its `rgba`), as an instruction names them."""
Axis = Literal["x", "y", "z"]
AXES = {"x": 0, "y": 1, "z": 2}


class Part(StrictModel):
    """One solid of an object: its shape, bounding half-extents and centre in the object's frame.

    `axis` is the long axis of a cylinder or capsule (a cylinder lying on its side has axis x or y)."""

    half: Vec3
    pos: Vec3 = (0.0, 0.0, 0.0)
    shape: str = "box"
    axis: Axis = "z"

    @model_validator(mode="after")
    def _consistent(self) -> "Part":
        if self.shape not in SHAPES:
            raise ValueError(f"unknown shape {self.shape!r}; known: {', '.join(SHAPES)}")
        if not all(math.isfinite(h) and h > 0 for h in self.half):
            raise ValueError(f"half-extents {self.half} must be positive numbers of metres")
        across = [h for i, h in enumerate(self.half) if i != AXES[self.axis]]
        if self.shape == "sphere" and not math.isclose(min(self.half), max(self.half), rel_tol=1e-6):
            raise ValueError(f"a sphere's half-extents are its radius three times, not {self.half}")
        if self.shape in ("cylinder", "capsule") and not math.isclose(*across, rel_tol=1e-6):
            raise ValueError(f"a {self.shape} along {self.axis} has one radius across its axis, not {across}")
        if self.shape == "capsule" and self.half[AXES[self.axis]] < across[0]:
            raise ValueError(f"a capsule's half-length {self.half[AXES[self.axis]]} is shorter than its radius")
        return self

    @property
    def radius(self) -> float:
        """Radius across the axis (cylinder, capsule, sphere); a box's smaller half-extent across z."""
        return min(h for i, h in enumerate(self.half) if i != AXES[self.axis])

    @property
    def volume(self) -> float:
        hx, hy, hz = self.half
        if self.shape == "box":
            return 8 * hx * hy * hz
        r, length = self.radius, 2 * self.half[AXES[self.axis]]
        if self.shape == "sphere":
            return 4 / 3 * math.pi * r ** 3
        if self.shape == "cylinder":
            return math.pi * r * r * length
        return math.pi * r * r * (length - 2 * r) + 4 / 3 * math.pi * r ** 3  # capsule

    def support(self, d: np.ndarray) -> np.ndarray:
        """The part's extent from its centre along directions (..., 3) in the object's frame: max over its
        points p of p . d (a box: sum |d_i| h_i; a sphere: r |d|; a cylinder or capsule split along its axis)."""
        d = np.asarray(d, float)
        if self.shape == "box":
            return np.abs(d) @ np.asarray(self.half)
        norm = np.linalg.norm(d, axis=-1)
        if self.shape == "sphere":
            return self.half[0] * norm
        a = np.abs(d[..., AXES[self.axis]])
        r, hl = self.radius, self.half[AXES[self.axis]]
        if self.shape == "cylinder":
            return hl * a + r * np.sqrt(np.maximum(norm * norm - a * a, 0.0))
        return (hl - r) * a + r * norm  # capsule: a segment swept by a ball

    def mjcf(self) -> tuple[str, str, str]:
        """(type, size, extra attributes) of this part as a MuJoCo geom."""
        if self.shape == "box":
            return "box", _f(*self.half), ""
        if self.shape == "sphere":
            return "sphere", _f(self.half[0]), ""
        hl = self.half[AXES[self.axis]]
        size = _f(self.radius, hl - self.radius if self.shape == "capsule" else hl)
        turn = {"x": ' quat="0.707107 0 0.707107 0"', "y": ' quat="0.707107 -0.707107 0 0"', "z": ""}[self.axis]
        return self.shape, size, turn


class Geometry(StrictModel):
    """An object's shape: one or more parts; the frame's origin is the first part's centre.

    `label` is what the object is called ("wooden board", "red cylinder"; empty: its name in the scene),
    `material` what it looks made of ("wood", "steel", "foam"; empty: not said), `colour` a name from
    `COLOURS` (empty: not said; `rgba` is what the camera renders either way)."""

    parts: tuple[Part, ...]
    rgba: RGBA = (0.7, 0.7, 0.7, 1.0)
    label: str = ""
    material: str = ""
    colour: str = ""

    @model_validator(mode="after")
    def _named_colour(self) -> "Geometry":
        if self.colour and self.colour not in COLOURS:
            raise ValueError(f"unknown colour {self.colour!r}; known: {', '.join(COLOURS)}")
        return self

    @property
    def rest_z(self) -> float:
        """Height of the frame's origin when the object lies on the table in its nominal orientation."""
        return -min(p.pos[2] - p.half[2] for p in self.parts)

    @property
    def volumes(self) -> list[float]:
        return [p.volume for p in self.parts]

    @property
    def height(self) -> float:
        return max(p.pos[2] + p.half[2] for p in self.parts) - min(p.pos[2] - p.half[2] for p in self.parts)

    @property
    def shape(self) -> str:
        """The shape of a one-part object; `2-part`, `3-part`, ... for an object of several parts (a board)."""
        return self.parts[0].shape if len(self.parts) == 1 else f"{len(self.parts)}-part"

    def support(self, d: np.ndarray) -> np.ndarray:
        """The object's extent from its origin along directions (..., 3) in its own frame."""
        d = np.asarray(d, float)
        return np.max([d @ np.asarray(p.pos) + p.support(d) for p in self.parts], axis=0)

    def bounds(self, pos: np.ndarray, quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounds (lo, hi), each (..., 3), of the object at poses (..., 3) / (..., 4):
        exact for every shape (a lying cylinder's bounds are not its rotated box's)."""
        rot = _rotation(np.asarray(quat, float))  # (..., 3, 3), object -> world
        eye = np.eye(3)
        local = np.einsum("...ji,kj->...ki", rot, eye)  # row k: world axis k in the object's frame
        hi = np.asarray(pos, float) + self.support(local)
        lo = np.asarray(pos, float) - self.support(-local)
        return lo, hi

    def lowest_z(self, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
        """Height of the object's lowest point at poses (..., 3) / (..., 4)."""
        return self.bounds(pos, quat)[0][..., 2]

    def surface_distance(self, point: np.ndarray) -> float:
        """Signed distance (m) of a point in the object's frame from its surface: < 0 inside, > 0 outside
        (the nearest part decides). A contact region's centre should be within a few mm of 0."""
        p = np.asarray(point, float)
        return float(min(_part_distance(part, p - np.asarray(part.pos)) for part in self.parts))


def _part_distance(part: Part, p: np.ndarray) -> float:
    h = np.asarray(part.half)
    if part.shape == "box":
        q = np.abs(p) - h
        return float(np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0))
    if part.shape == "sphere":
        return float(np.linalg.norm(p) - part.half[0])
    i = AXES[part.axis]
    along, across = abs(p[i]), float(np.linalg.norm(np.delete(p, i)))
    r, hl = part.radius, part.half[i]
    if part.shape == "capsule":
        return float(math.hypot(max(along - (hl - r), 0.0), across) - r)
    q = np.array([across - r, along - hl])
    return float(np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0))


def box_corners(geo: Geometry) -> np.ndarray:
    """(8 x parts, 3) corners of every part's bounding box, object frame (exact hull points for boxes)."""
    out = []
    for p in geo.parts:
        for s in itertools.product((-1, 1), repeat=3):
            out.append(np.asarray(p.pos) + np.asarray(s) * np.asarray(p.half))
    return np.array(out)


def _rotation(quat: np.ndarray) -> np.ndarray:
    w, x, y, z = (quat[..., i] for i in range(4))
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1)], axis=-2)


def _f(*xs: float) -> str:
    return " ".join(f"{x:.6g}" for x in xs)


class Physics(StrictModel):
    """Mass (kg) and friction against the table of one object: truth or belief, see the module doc."""

    mass_kg: float
    friction: float


class Placement(StrictModel):
    x: float
    y: float
    yaw_deg: float = 0.0

    def quat(self) -> tuple[float, float, float, float]:
        h = math.radians(self.yaw_deg) / 2
        return (math.cos(h), 0.0, 0.0, math.sin(h))


class Fixture(StrictModel):
    """A static box (wall, curb, obstacle): half-extents and centre in the world; `label` as a user says it."""

    half: Vec3
    pos: Vec3
    rgba: RGBA = (0.45, 0.45, 0.5, 1.0)
    label: str = ""


class Marker(StrictModel):
    """A visual-only disc on the table (a goal region); no collisions; `label` as a user says it."""

    x: float
    y: float
    radius: float
    rgba: RGBA = (0.1, 0.8, 0.2, 0.45)
    label: str = ""


def box(size: Vec3, rgba: RGBA, label: str = "", material: str = "") -> Geometry:
    return Geometry(parts=(Part(half=(size[0] / 2, size[1] / 2, size[2] / 2)),), rgba=rgba, label=label,
                    material=material)


def cylinder(diameter: float, length: float, rgba: RGBA, axis: Axis = "z", label: str = "",
             material: str = "") -> Geometry:
    """A cylinder; axis z stands it on its flat end (a puck, a can), x or y lays it on its side."""
    half = [diameter / 2] * 3
    half[AXES[axis]] = length / 2
    return Geometry(parts=(Part(half=tuple(half), shape="cylinder", axis=axis),), rgba=rgba, label=label,
                    material=material)


def sphere(diameter: float, rgba: RGBA, label: str = "", material: str = "") -> Geometry:
    r = diameter / 2
    return Geometry(parts=(Part(half=(r, r, r), shape="sphere"),), rgba=rgba, label=label, material=material)


def capsule(diameter: float, length: float, rgba: RGBA, axis: Axis = "z", label: str = "",
            material: str = "") -> Geometry:
    """A capsule `length` long overall (caps included)."""
    half = [diameter / 2] * 3
    half[AXES[axis]] = length / 2
    return Geometry(parts=(Part(half=tuple(half), shape="capsule", axis=axis),), rgba=rgba, label=label,
                    material=material)


def board(plate: tuple[float, float], handle: tuple[float, float], thickness: float,
          rgba: RGBA, label: str = "", material: str = "") -> Geometry:
    """Plate centred at the origin, handle sticking out along +x."""
    t = thickness / 2
    return Geometry(parts=(
        Part(half=(plate[0] / 2, plate[1] / 2, t)),
        Part(half=(handle[0] / 2, handle[1] / 2, t), pos=(plate[0] / 2 + handle[0] / 2, 0.0, 0.0)),
    ), rgba=rgba, label=label, material=material)
