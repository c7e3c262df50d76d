"""Peg shapes and their matching holes, in metres.

A hole is a convex polygon given as half-planes (outward normal angle, inset
distance) so that one wall box per side reproduces it exactly; MuJoCo only
collides convex geoms, so a round hole is a many-sided polygon.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.peg.config import PegTaskConfig

MM = 1e-3


@dataclass(frozen=True)
class PegShape:
    name: str
    kind: str  # "cylinder" | "box" | "prism"
    half_y: float  # half extent along y (the image plane)
    half_x: float  # half extent along x (depth)
    sides: int = 0  # prism only
    circumradius: float = 0.0  # prism only

    def prism_vertices(self, half_length: float) -> list[tuple[float, float, float]]:
        """Vertices of a regular prism with one flat side facing +y."""
        verts = []
        for k in range(self.sides):
            a = 2 * math.pi * k / self.sides + math.pi / self.sides
            for z in (-half_length, half_length):
                verts.append((self.circumradius * math.sin(a), self.circumradius * math.cos(a), z))
        return verts

    def width(self, directions: np.ndarray) -> np.ndarray:
        """Extent of the cross-section along each unit direction (rows of (x, y))."""
        if self.kind == "cylinder":
            return np.full(len(directions), 2 * self.half_y)
        if self.kind == "box":
            corners = np.array([(sx * self.half_x, sy * self.half_y) for sx in (-1, 1) for sy in (-1, 1)])
        else:
            corners = np.array([(x, y) for x, y, z in self.prism_vertices(1.0) if z > 0])
        along = directions @ corners.T
        return along.max(axis=1) - along.min(axis=1)


@dataclass(frozen=True)
class HoleShape:
    """Half-planes (normal angle in the x-y plane from +y, distance from the axis)."""

    sides: tuple[tuple[float, float], ...]

    def vertices(self) -> list[tuple[float, float]]:
        """(x, y) corners of the opening: where neighbouring walls' inner faces meet."""
        sides = sorted(self.sides)
        out = []
        for (a1, d1), (a2, d2) in zip(sides, sides[1:] + sides[:1]):
            # Solve sin(a) x + cos(a) y = d for both walls.
            det = math.sin(a1) * math.cos(a2) - math.cos(a1) * math.sin(a2)
            out.append(((d1 * math.cos(a2) - d2 * math.cos(a1)) / det,
                        (math.sin(a1) * d2 - math.sin(a2) * d1) / det))
        return out

    @property
    def y_range(self) -> tuple[float, float]:
        """The opening's extent along y (odd polygons are not symmetric about the axis)."""
        ys = [y for _, y in self.vertices()]
        return min(ys), max(ys)

    @property
    def x_range(self) -> tuple[float, float]:
        """The opening's extent along x (what the side camera sees)."""
        xs = [x for x, _ in self.vertices()]
        return min(xs), max(xs)

    def contains(self, x: float, y: float) -> bool:
        """Is the point (relative to the hole axis) inside the opening's footprint?"""
        return all(math.sin(a) * x + math.cos(a) * y <= d for a, d in self.sides)

    def width(self, directions: np.ndarray) -> np.ndarray:
        """Extent of the opening along each unit direction (rows of (x, y))."""
        along = directions @ self._corners_t
        return along.max(axis=1) - along.min(axis=1)

    @cached_property
    def _corners_t(self) -> np.ndarray:
        """`vertices()` as a (2, n) array, computed once (the scorer asks for widths while a trial runs)."""
        return np.array(self.vertices()).T


def gap_along(peg: PegShape, hole: HoleShape, direction: tuple[float, float]) -> float:
    """Hole width minus peg width along a horizontal unit direction (x, y), peg unrotated.

    Across a round hole's flats or a square's sides this is the configured clearance;
    along a square's diagonal it is sqrt(2) times that.
    """
    n = np.array([direction], dtype=float)
    return float(hole.width(n)[0] - peg.width(n)[0])


SHAPES_HELP = "round, square, rectangle, or polygonN (regular N-sided prism, N >= 3)"


def peg_shape(name: str, cfg: PegTaskConfig) -> PegShape:
    p = cfg.peg
    if name == "round":
        r = p.diameter_mm / 2 * MM
        return PegShape(name, "cylinder", r, r)
    if name == "square":
        h = p.square_mm / 2 * MM
        return PegShape(name, "box", h, h)
    if name == "rectangle":
        return PegShape(name, "box", p.rectangle_mm[0] / 2 * MM, p.rectangle_mm[1] / 2 * MM)
    m = re.fullmatch(r"polygon(\d+)", name)
    if m and int(m.group(1)) >= 3:
        n = int(m.group(1))
        rc = p.polygon_circumradius_mm * MM
        inradius = rc * math.cos(math.pi / n)
        half_y = inradius if n % 2 == 0 else rc  # flat side faces +y
        return PegShape(name, "prism", half_y, rc, sides=n, circumradius=rc)
    raise ConfigError(f"unknown peg shape {name!r}; known: {SHAPES_HELP}")


def hole_for(peg: PegShape, cfg: PegTaskConfig) -> HoleShape:
    c = cfg.peg.clearance_mm / 2 * MM
    if peg.kind == "cylinder":
        n = cfg.hole.round_sides
        return HoleShape(tuple((2 * math.pi * k / n, peg.half_y + c) for k in range(n)))
    if peg.kind == "box":
        return HoleShape(((0.0, peg.half_y + c), (math.pi, peg.half_y + c),
                          (math.pi / 2, peg.half_x + c), (3 * math.pi / 2, peg.half_x + c)))
    n = peg.sides
    inradius = peg.circumradius * math.cos(math.pi / n) + c
    # Side normals of the prism: angles (from +y) at 2*pi*(k+1/2)/n + pi/n offset -> flat side faces +y.
    return HoleShape(tuple((2 * math.pi * k / n, inradius) for k in range(n)))
