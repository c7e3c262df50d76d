"""Typed requests and replies of system C's reasoner roles (CoRAL): physics priors and contact regions.

What a role may see is what a model would: the instruction, a camera image, and each object's label
and size as its known 3D model gives them. Never a trial's true mass or friction.
Replies are parsed strictly (unknown keys rejected); numbers a model may get wrong but that are
usable once bounded (a mass of 80 kg for a box) are clamped by `kintsugi.reasoning.priors`, with
a note, rather than rejected.
"""

from __future__ import annotations

import math

from pydantic import Field, field_validator

from kintsugi.config import StrictModel

Vec3 = tuple[float, float, float]


class ObjectView(StrictModel):
    """One object as the robot knows it before touching it."""

    label: str = Field(min_length=1, max_length=80, description="what the object is, e.g. 'cutting board'")
    size_m: Vec3 = Field(description="bounding-box extents of its known model, metres (x, y, z)")

    @field_validator("size_m")
    @classmethod
    def _positive(cls, v: Vec3) -> Vec3:
        if not all(math.isfinite(x) and x > 0 for x in v):
            raise ValueError("every extent must be a positive finite number of metres")
        return v


class PriorsRequest(StrictModel):
    task: str = Field(description="the instruction")
    objects: list[ObjectView] = Field(min_length=1, max_length=32)
    image_png: bytes | None = Field(default=None, repr=False, description="a camera image of the scene")


class ObjectPrior(StrictModel):
    mass_kg: float = Field(description="estimated mass, kg")
    friction: float = Field(description="estimated sliding friction coefficient against the table")
    material: str = Field(default="", max_length=80, description="what it looks made of (free text)")


class PriorsReply(StrictModel):
    objects: dict[str, ObjectPrior] = Field(description="label -> prior, one entry per requested object")
    reasoning: str = Field(default="", max_length=2000)


class RegionSpec(StrictModel):
    """A contact region on an object, in the object's frame: candidate contact points are sampled on
    the disc of `radius` around `center`, and the hand approaches against `normal` (outward)."""

    object: str = Field(min_length=1, max_length=80)
    center: Vec3
    normal: Vec3
    radius: float
