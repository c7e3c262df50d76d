"""Cost terms over a batch of planning rollouts, vectorized over the K samples (numpy only).

A `View` reads a `RolloutBatch` through the trial's `Layout` (tool centre point, yaw,
gripper opening, tared wrist force, touch pads, object poses) and remembers the observation
the plan started from. Terms return (K, T) running costs; `total` averages them over the
horizon and adds a terminal weight on the last step. Contact regions (centre, normal,
radius, in an object's frame) yield candidate contact points that act as soft attractors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.world import Layout, rotate, tared_force_world, up_axis

EPS = 1e-3


class View:
    """Named quantities of a rollout batch, each (K, T, ...)."""

    def __init__(self, batch, layout: Layout, obs: Observation) -> None:  # noqa: ANN001 - a RolloutBatch
        self.batch = batch
        self.layout = layout
        self.obs = obs

    @cached_property
    def tcp(self) -> np.ndarray:
        return self.batch.sensor("tcp_pos")

    @cached_property
    def yaw(self) -> np.ndarray:
        return self.batch.qpos[:, :, self.layout.ee_qpos[3]]

    @cached_property
    def opening(self) -> np.ndarray:
        return self.batch.qpos[:, :, self.layout.finger_qpos].sum(axis=-1)

    @cached_property
    def force(self) -> np.ndarray:
        """What the hand pushes on its surroundings with, world frame, tared (as the robot reads it)."""
        return tared_force_world(self.batch.sensor("ft_force"), self.yaw, self.layout.hand_weight_n)

    @cached_property
    def touch(self) -> np.ndarray:
        return np.concatenate([self.batch.sensor("touch_l"), self.batch.sensor("touch_r")], axis=-1)

    @cached_property
    def ctrl(self) -> np.ndarray:
        return self.batch.controls

    def pos(self, name: str) -> np.ndarray:
        return self.batch.sensor(f"{name}_pos")

    def quat(self, name: str) -> np.ndarray:
        return self.batch.sensor(f"{name}_quat")

    def vel(self, name: str) -> np.ndarray:
        return self.batch.sensor(f"{name}_vel")

    def up(self, name: str) -> np.ndarray:
        return up_axis(self.quat(name))

    def to_world(self, name: str, local: np.ndarray) -> np.ndarray:
        """Points (J, 3) in object `name`'s frame -> (K, T, J, 3) along each rollout."""
        q = self.quat(name)[:, :, None, :]
        p = self.pos(name)[:, :, None, :]
        return p + rotate(np.broadcast_to(q, (*q.shape[:2], len(local), 4)), local[None, None])


def norm(v: np.ndarray) -> np.ndarray:
    """Smooth Euclidean norm over the last axis (differentiable at zero, in metres)."""
    return np.sqrt((v * v).sum(axis=-1) + EPS * EPS) - EPS


def total(running: np.ndarray, terminal_weight: float = 1.0) -> np.ndarray:
    """(K, T) running cost -> (K,): mean over the horizon plus `terminal_weight` x the last step."""
    return running.mean(axis=1) + terminal_weight * running[:, -1]


def smoothness(view: View) -> np.ndarray:
    """(K, T) squared change of the commanded x, y, z (m per step): discourages jitter."""
    d = np.diff(view.ctrl[:, :, :3], axis=1, prepend=view.ctrl[:, :1, :3])
    return (d * d).sum(axis=-1)


def yaw_error(yaw: np.ndarray, target: float, period: float = math.pi) -> np.ndarray:
    """Signed distance to the nearest of target + k * period (a box grasped across is symmetric)."""
    return (yaw - target + period / 2) % period - period / 2


def step_up(x: np.ndarray, edge: float, width: float) -> np.ndarray:
    """Smooth 0 -> 1 as x rises through [edge - width, edge + width] (a soft stage switch)."""
    return 1.0 / (1.0 + np.exp(-(x - edge) / (width / 3)))


@dataclass(frozen=True)
class ContactRegion:
    """Where to touch an object: a disc (centre, outward normal, radius) in the object's frame.

    `standoff` is how far from the surface, along the normal, the tool centre point sits when
    the fingers touch it; `drop` lowers it (the TCP is the fingertips' bottom, so to touch a
    point on a side face the TCP goes a little below it).
    """

    obj: str
    center: tuple[float, float, float]
    normal: tuple[float, float, float]
    radius: float
    standoff: float = 0.0
    drop: float = 0.0

    def sample(self, count: int, seed: int = 0) -> np.ndarray:
        """(count, 3) candidate contact points in the object's frame, spread over the disc;
        the centre is always the first."""
        n = np.asarray(self.normal, float)
        n /= np.linalg.norm(n)
        a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = np.cross(n, a)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        rng = np.random.default_rng(seed)
        r = self.radius * np.sqrt(rng.uniform(0, 1, count))
        th = rng.uniform(0, 2 * np.pi, count)
        pts = np.asarray(self.center) + r[:, None] * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2)
        pts[0] = self.center
        return pts

    def tcp_targets(self, points: np.ndarray) -> np.ndarray:
        """Where the TCP goes to touch each candidate point (object frame)."""
        n = np.asarray(self.normal, float)
        n /= np.linalg.norm(n)
        return points + self.standoff * n - np.array([0.0, 0.0, self.drop])


class Attractor:
    """Soft attraction of the TCP to the nearest of a region's candidate points, following the object."""

    def __init__(self, region: ContactRegion, count: int, seed: int = 0) -> None:
        self.region = region
        self.points = region.sample(count, seed)
        self.targets = region.tcp_targets(self.points)

    def distance(self, view: View) -> np.ndarray:
        """(K, T) distance from the TCP to the nearest candidate target."""
        world = view.to_world(self.region.obj, self.targets)  # (K, T, J, 3)
        return norm(view.tcp[:, :, None, :] - world).min(axis=-1)

    def world_points(self, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
        """Candidate contact points in the world for one object pose (drawing, checks)."""
        return pos + rotate(np.broadcast_to(quat, (len(self.points), 4)), self.points)

    def world_targets(self, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
        return pos + rotate(np.broadcast_to(quat, (len(self.targets), 4)), self.targets)
