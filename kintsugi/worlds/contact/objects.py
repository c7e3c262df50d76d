"""What a contact scene is made of, split the way the paper splits knowledge.

- `Geometry`: an object's shape, as its known 3D model gives it (CoRAL gets object meshes).
- `Physics`: mass and friction. In the evaluation world these are the TRUTH; in the
  planning world the same type holds BELIEFS (`Beliefs`), set from a prior or from
  system identification. Nothing in a method may build a `Physics` from the evaluation
  world, except the oracle baselines, through `oracle_beliefs` (see beliefs.py).
- `Placement`: where an object starts on the table.
"""

from __future__ import annotations

import math

from kintsugi.core.config import StrictModel

Vec3 = tuple[float, float, float]


class Part(StrictModel):
    """One box of an object: half-extents and centre in the object's frame."""

    half: Vec3
    pos: Vec3 = (0.0, 0.0, 0.0)


class Geometry(StrictModel):
    """An object's shape: one or more boxes; the frame's origin is the first part's centre."""

    parts: tuple[Part, ...]
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)

    @property
    def rest_z(self) -> float:
        """Height of the frame's origin when the object lies on the table in its nominal orientation."""
        return -min(p.pos[2] - p.half[2] for p in self.parts)

    @property
    def volumes(self) -> list[float]:
        return [8 * p.half[0] * p.half[1] * p.half[2] for p in self.parts]

    @property
    def height(self) -> float:
        return max(p.pos[2] + p.half[2] for p in self.parts) - min(p.pos[2] - p.half[2] for p in self.parts)


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
    """A static box (wall, curb): half-extents and centre in the world."""

    half: Vec3
    pos: Vec3
    rgba: tuple[float, float, float, float] = (0.45, 0.45, 0.5, 1.0)


class Marker(StrictModel):
    """A visual-only disc on the table (a goal region); no collisions."""

    x: float
    y: float
    radius: float
    rgba: tuple[float, float, float, float] = (0.1, 0.8, 0.2, 0.45)


def box(size: Vec3, rgba: tuple[float, float, float, float]) -> Geometry:
    return Geometry(parts=(Part(half=(size[0] / 2, size[1] / 2, size[2] / 2)),), rgba=rgba)


def board(plate: tuple[float, float], handle: tuple[float, float], thickness: float,
          rgba: tuple[float, float, float, float]) -> Geometry:
    """Plate centred at the origin, handle sticking out along +x."""
    t = thickness / 2
    return Geometry(parts=(
        Part(half=(plate[0] / 2, plate[1] / 2, t)),
        Part(half=(handle[0] / 2, handle[1] / 2, t), pos=(plate[0] / 2 + handle[0] / 2, 0.0, 0.0)),
    ), rgba=rgba)
