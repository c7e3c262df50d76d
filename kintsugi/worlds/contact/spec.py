"""What a contact task declares: its config, how a trial's world is drawn, and its ground-truth scoring.

A task file (pick_box.py, ...) builds one `ContactTaskDef`; task.py runs any of them. The
scorer watches the evaluation world at the robot's inner rate (for goals about history,
like "pushed with 5 N for 2 s") and judges the end; it is never shown to a method.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.worlds.contact.objects import Geometry, Physics, box_corners
from kintsugi.worlds.contact.world import EvaluationWorld, Scene, rotate


@dataclass(frozen=True)
class TrialSetup:
    """One trial's draws: the scene, the TRUE physics (evaluation world only), the nominal
    physics (the middle of the ranges: world side, never in a non-oracle method's context),
    and the drawn numbers for the record."""

    scene: Scene
    truth: dict[str, Physics]
    nominal: dict[str, Physics]
    params: dict[str, float]


class Scorer(Protocol):
    """Ground-truth judge of one attempt; sees the evaluation world, never shown to a method."""

    def reset(self) -> None: ...

    def watch(self, world: EvaluationWorld) -> None: ...

    def finish(self, world: EvaluationWorld) -> tuple[bool, StrictModel]: ...


@dataclass(frozen=True)
class ContactTaskDef:
    name: str
    description: str
    instruction: str
    config_type: type[ContactConfig]
    build: Callable[[ContactConfig, Drawer], TrialSetup]
    scorer: Callable[[ContactConfig, TrialSetup], Scorer]
    target: str
    """The object the task is about (sysid fits its mass and friction)."""
    reference_method: str = "coral"
    """The method that proves the task (the task contract runs it). `coral` needs nothing written for
    the task (the instruction's words choose its costs); `expert-fsm` and `mppi-sysid` need a hand-written
    expert in `kintsugi.methods.expert.designs`, so only a task that has one names `expert-fsm`."""


def corners(geo: Geometry) -> np.ndarray:
    """(8 x parts, 3) corners of each part's bounding box in the object's frame (a box's own corners)."""
    return box_corners(geo)


def lowest_z(world: EvaluationWorld, name: str) -> float:
    """Height of an object's lowest point above the table top (ground truth), as its shape gives it: a box's
    lowest corner, a cylinder's rim, a sphere's or capsule's bottom."""
    pos, quat = world.object_pose(name)
    geo = world.scene.geometry[name]
    if all(p.shape == "box" for p in geo.parts):
        pts = pos + rotate(np.broadcast_to(quat, (len(c := corners(geo)), 4)), c)
        return float(pts[:, 2].min())
    return float(geo.lowest_z(pos, quat))


def nominal(mass: tuple[float, float], friction: tuple[float, float]) -> Physics:
    return Physics(mass_kg=(mass[0] + mass[1]) / 2, friction=(friction[0] + friction[1]) / 2)
