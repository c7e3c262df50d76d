"""What a tabletop task declares: its objects, regions, instruction, goal predicates, scoring and script.

A task file (e.g. pour_single.py, stack_blocks.py) builds one `TaskSpec`; task.py runs any spec. Objects
beyond the built-in ones (bottle, cup, ...) and regions are declared in the spec itself (`declared`,
`regions`): they become the task's own config sections, so `--set objects.red_block.mass_kg=0.2` and
`kintsugi config <task>` see them, and no shared config changes. Goal
predicates are text a planner or reasoner reads (`poured(bottle, cup)`); the
`Scorer` checks the same goal on ground truth, watching the world every control
tick (for goals about history, like "was tilted over the cup") and at the end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Mapping, Protocol

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.tabletop.config import ObjectSection, Region, TabletopConfig
from kintsugi.worlds.tabletop.world import GroundTruth, TabletopWorld

if TYPE_CHECKING:
    from kintsugi.worlds.tabletop.objects import Shape


class Scorer(Protocol):
    """Ground-truth judge of one trial; sees the world, never shown to a method."""

    def watch(self, world: TabletopWorld) -> None: ...

    def finish(self, world: TabletopWorld) -> tuple[bool, StrictModel]: ...


Script = Callable[[Any], list[Any]]
"""First `Observation` -> the nominal sequence of action dicts (no checks, no recovery). An entry may
instead be a callable `Observation -> dict | list[dict]`, expanded with a fresh observation when
its turn comes (`task.expand`)."""


@dataclass(frozen=True)
class TaskSpec:
    name: str
    description: str
    objects: tuple[str, ...]
    instruction: str
    goal: tuple[str, ...]
    script: Script
    scorer: Callable[[TabletopConfig], Scorer]
    targets: tuple[str, ...] = ()
    shift: tuple[str, tuple[int, int]] | None = None
    """`shift` condition: the object slid and the window of action indices (0-based) it happens in."""
    knock: tuple[str, tuple[int, int]] | None = None
    """`knock` condition: the standing object pushed over, and its action window; None: no such condition."""
    declared: Mapping[str, ObjectSection] = field(default_factory=dict)
    """Objects of this task's own (name -> shape, size, mass, friction, colour, start ranges); each is also
    listed in `objects`."""
    regions: Mapping[str, Region] = field(default_factory=dict)
    """Regions of this task's own (name -> centre, half-extents, `relative_to`), beside the shared ones;
    those it uses are listed in `targets`."""


# --- ground-truth predicates shared by the tasks' scorers ------------------------

def upright(truth: GroundTruth, obj: str, tol_deg: float, shape: "Shape | None" = None) -> bool:
    """Standing within tol_deg of vertical. With its `shape` given, a solid object whose two ends nothing tells
    apart (no painted cap, no opening: a can, a capsule, a cube) stands upright on either end."""
    tilt = truth.objects[obj].tilt_deg
    return tilt <= tol_deg or (shape is not None and end_free(shape) and tilt >= 180.0 - tol_deg)


def end_free(shape: "Shape") -> bool:
    """Its two ends look and behave alike: turned end over end it is the same object in the same pose."""
    return shape.kind != "sphere" and not shape.cap and shape.wall is None


def on_table(truth: GroundTruth, obj: str, rest_height: float, tol_m: float = 0.005) -> bool:
    """Resting upright on the table: its centre at its standing height."""
    return abs(truth.objects[obj].pos[2] - rest_height) <= tol_m


def at_rest(truth: GroundTruth, obj: str, speed_m_s: float) -> bool:
    return truth.objects[obj].speed_m_s <= speed_m_s


def held(truth: GroundTruth, obj: str) -> bool:
    return any(obj in objs for objs in truth.held.values())


def tilt_deg(axis: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip(axis[2], -1.0, 1.0))))


def region_center(cfg: TabletopConfig, name: str, truth: GroundTruth) -> np.ndarray:
    """A target region's centre now (a region beside an object moves with it)."""
    r = cfg.targets[name]
    c = np.array(r.center_m, float)
    if r.relative_to is not None:
        c = c + np.array(truth.objects[r.relative_to].pos[:2])
    return c


def in_region(cfg: TabletopConfig, name: str, truth: GroundTruth, obj: str) -> bool:
    """The object's centre lies inside the region (its half-extents along world x and y)."""
    d = np.abs(np.array(truth.objects[obj].pos[:2]) - region_center(cfg, name, truth))
    return bool(np.all(d <= np.array(cfg.targets[name].half_m)))


def rest_level(truth: GroundTruth, obj: str, rest_height: float, tol_deg: float, tol_m: float = 0.005,
               shape: "Shape | None" = None) -> bool:
    """Lying flat on the table: the body's z axis up and its centre at its rest height. With its `shape` given, a
    shape that is the same turned over (a utensil made of flat slabs) lies flat on either face."""
    return upright(truth, obj, tol_deg, shape) and on_table(truth, obj, rest_height, tol_m)
