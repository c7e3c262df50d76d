"""The `shift` and `knock` disturbances: something outside the robot moves a task's object.

`shift`: an external hand slides the task's target object (the cup, the plate, the tray...)
across the table by a drawn distance, during a drawn action of the task's window.
`knock`: a horizontal push at the top of a standing object (the bottle, the capsule) tips it over.
Both act on the physics only (the slide sets the body's pose and velocity tick by tick, the
push is an external force); the robot learns of them only through its cameras. Each draws
its random numbers up front from its own stream, so trial i of every condition and method
meets the same disturbance. Neither acts on an object a gripper touches: then it is skipped
and the skip is recorded.
"""

from __future__ import annotations

import math

import numpy as np

from kintsugi.worlds.tabletop.config import DisturbanceSection
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.world import TabletopWorld

DIRECTION_DRAWS = 16
"""Candidate directions drawn per disturbance; the first whose path is clear of the other objects wins."""
LATEST_FRACTION = 0.8
"""The disturbance starts in the first 80 % of its action (before a grasp closes on it)."""


def _touched(world: TabletopWorld, obj: str) -> bool:
    return any(obj in world.pad_contacts(arm)[0] for arm in ("left", "right"))


class _Timed:
    """Counts the task's atomic actions and fires once, at a drawn instant of a drawn one."""

    def __init__(self, world: TabletopWorld, obj: str, window: tuple[int, int], rng: np.random.Generator) -> None:
        self._world = world
        self.obj = obj
        self._action_index = -1
        self._fire_in = int(rng.integers(window[0], window[1] + 1))
        self._fraction = float(rng.uniform(0.0, LATEST_FRACTION))
        self._at: float | None = None
        self.fired = False
        self.events: list[tuple[float, str]] = []

    def begin_action(self, planned_s: float, arms: tuple[str, ...]) -> None:
        self._action_index += 1
        if self._action_index == self._fire_in and not self.fired:
            self._at = float(self._world.data.time) + self._fraction * planned_s

    def due(self, world: TabletopWorld) -> bool:
        if self.fired or self._at is None or world.data.time < self._at:
            return False
        self.fired = True
        if _touched(world, self.obj):
            self.events.append((float(world.data.time), f"{self.kind} of {self.obj} skipped: a gripper touches it"))
            return False
        return True

    kind = "disturbance"


def _clear_direction(world: TabletopWorld, obj: str, reach: float, angles: np.ndarray) -> float:
    """The first drawn direction along which `obj` can travel `reach` without meeting another object."""
    p = world.data.xpos[world.bodies[obj]][:2]
    r = shape_of(obj, world.cfg.objects)
    own = r.radius if r.kind == "cylinder" else float(np.hypot(*r.half_extents[:2]))
    for a in angles:
        d = np.array([math.cos(a), math.sin(a)])
        clear = True
        for other in world.objects:
            if other == obj:
                continue
            q = world.data.xpos[world.bodies[other]][:2]
            s = shape_of(other, world.cfg.objects)
            size = s.radius if s.kind == "cylinder" else float(np.hypot(*s.half_extents[:2]))
            t = float(np.clip((q - p) @ d, 0.0, reach))  # closest approach along the path
            if np.linalg.norm(p + t * d - q) < own + size + 0.01:
                clear = False
                break
        if clear:
            return float(a)
    return float(angles[0])


class ShiftDisturbance(_Timed):
    """Slides `obj` by a drawn distance in a clear direction over `shift_duration_s`."""

    kind = "shift"

    def __init__(self, world: TabletopWorld, obj: str, window: tuple[int, int], cfg: DisturbanceSection,
                 seed: int) -> None:
        rng = np.random.default_rng([seed, 0x5817])
        super().__init__(world, obj, window, rng)
        self.distance = float(rng.uniform(*cfg.shift_m))
        self._angles = rng.uniform(-math.pi, math.pi, DIRECTION_DRAWS)
        self.duration = cfg.shift_duration_s
        jnt = world.model.body_jntadr[world.bodies[obj]]
        self._qpos = int(world.model.jnt_qposadr[jnt])
        self._dof = int(world.model.jnt_dofadr[jnt])
        self._slide: tuple[float, np.ndarray, np.ndarray] | None = None

    def __call__(self, world: TabletopWorld) -> None:
        if self.due(world):
            a = _clear_direction(world, self.obj, self.distance, self._angles)
            d = self.distance * np.array([math.cos(a), math.sin(a)])
            self._slide = (float(world.data.time), world.data.qpos[self._qpos:self._qpos + 2].copy(), d)
            self.events.append((float(world.data.time), f"{self.obj} slid {self.distance * 100:.1f} cm towards "
                                                         f"{math.degrees(a):.0f} deg"))
        if self._slide is None:
            return
        t0, start, d = self._slide
        s = min((world.data.time - t0) / self.duration, 1.0)
        world.data.qpos[self._qpos:self._qpos + 2] = start + (s * s * (3 - 2 * s)) * d
        rate = 6 * s * (1 - s) / self.duration
        world.data.qvel[self._dof:self._dof + 2] = rate * d
        world.data.qvel[self._dof + 3:self._dof + 6] = 0.0  # slid, not spun
        if s >= 1.0:
            world.data.qvel[self._dof:self._dof + 6] = 0.0
            self._slide = None


class KnockDisturbance(_Timed):
    """Pushes `obj` horizontally at its top (`knock_push` x its weight, for `knock_duration_s`)."""

    kind = "knock"

    def __init__(self, world: TabletopWorld, obj: str, window: tuple[int, int], cfg: DisturbanceSection,
                 seed: int) -> None:
        rng = np.random.default_rng([seed, 0x4E0C])
        super().__init__(world, obj, window, rng)
        self._angles = rng.uniform(-math.pi, math.pi, DIRECTION_DRAWS)
        self.push = cfg.knock_push
        self.duration = cfg.knock_duration_s
        self._body = world.bodies[obj]
        self._until: float | None = None
        self._force = np.zeros(3)

    def __call__(self, world: TabletopWorld) -> None:
        if self.due(world):
            s = shape_of(self.obj, world.cfg.objects)
            height = 2 * s.rest_height
            a = _clear_direction(world, self.obj, height, self._angles)
            mass = float(world.model.body_subtreemass[self._body])
            self._force = self.push * mass * 9.81 * np.array([math.cos(a), math.sin(a), 0.0])
            self._until = float(world.data.time) + self.duration
            self.events.append((float(world.data.time), f"{self.obj} knocked towards {math.degrees(a):.0f} deg"))
        if self._until is None:
            return
        xfrc = world.data.xfrc_applied[self._body]
        if world.data.time >= self._until:
            xfrc[:] = 0.0
            self._until = None
            return
        top = world.data.xipos[self._body].copy()
        axis = world.data.xmat[self._body].reshape(3, 3)[:, 2]
        lever = top + shape_of(self.obj, world.cfg.objects).rest_height * axis - world.data.xipos[self._body]
        xfrc[:3] = self._force
        xfrc[3:] = np.cross(lever, self._force)  # the push acts at the top, not at the centre of mass


class Disturbances:
    """Several disturbances behind the robot's one action hook and the world's one watcher slot."""

    def __init__(self, parts: list) -> None:  # noqa: ANN001 - any objects with begin_action/__call__/events
        self.parts = parts

    def begin_action(self, planned_s: float, arms: tuple[str, ...]) -> None:
        for p in self.parts:
            p.begin_action(planned_s, arms)

    def __call__(self, world: TabletopWorld) -> None:
        for p in self.parts:
            p(world)

    @property
    def events(self) -> list[tuple[float, str]]:
        return sorted(e for p in self.parts for e in p.events)
