"""The feature vector the constraints read (Eq. 1): per-object geometry and per-arm gripper signals.

Structural types only, so perception's `ObjectFeatures` (attributes `.centroid`, `.axis`,
`.n_points`, ...) plugs in without this package importing any task or perception code.
Everything here is measured by the robot's own sensors and cameras, never simulator truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Collection, Mapping, Protocol, Sequence

Vec = Sequence[float]
"""A 3-vector: tuple, list or numpy array."""

ARM_FEATURES = frozenset({"eef", "opening", "closed", "touching"})
"""What every arm reports; object features are whatever perception supplies (see Vocabulary)."""

OBJECT_FEATURES = frozenset({"centroid", "axis", "n_points", "extent"})
"""The object features the built-in constraint templates read directly."""


class ObjectLike(Protocol):
    """One perceived object: centroid (m, world frame), principal axis (sign-free), points seen.

    `centroid` and `axis` may be None when the object is not visible this step. Further vector
    features (e.g. `top`) are read by name as attributes or from an optional `extremes` mapping.
    """

    @property
    def centroid(self) -> Vec | None: ...
    @property
    def axis(self) -> Vec | None: ...
    @property
    def n_points(self) -> int: ...


class ArmLike(Protocol):
    """One arm's proprioception: end-effector position, gripper opening (m), closed flag, contacts."""

    @property
    def eef(self) -> Vec: ...
    @property
    def opening(self) -> float: ...
    @property
    def closed(self) -> bool: ...
    @property
    def touching(self) -> Collection[str]: ...


@dataclass(frozen=True, slots=True)
class ObjectState:
    """A plain ObjectLike, for worlds without their own feature type (and for tests)."""

    centroid: Vec
    axis: Vec = (0.0, 0.0, 1.0)
    n_points: int = 1000


@dataclass(frozen=True, slots=True)
class ArmState:
    """A plain ArmLike. `touching` names the objects in contact with the fingers."""

    eef: Vec
    opening: float = 0.08
    closed: bool = False
    touching: frozenset[str] = frozenset()


@dataclass(frozen=True, slots=True)
class Features:
    """The feature vector at one control step: objects and arms by name.

    An object perception lost this step is simply absent; constraints over it read NaN
    (undecided) except visibility, which reads zero points.
    """

    objects: Mapping[str, ObjectLike] = field(default_factory=dict)
    arms: Mapping[str, ArmLike] = field(default_factory=dict)
