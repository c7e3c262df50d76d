"""Building blocks the hand-written expert costs share: grasp geometry and stock stages.

An expert knows the task, its robot (finger sizes, opening) and the objects' shapes; it
reads the measured state only through `Observation` (tracker poses, proprioception, F/T).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.contact.context import ContactContext
from kintsugi.methods.mppi.costs import View, norm, smoothness, total, yaw_error
from kintsugi.methods.mppi.fsm import Stage, StageFactory
from kintsugi.worlds.contact.objects import Geometry
from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.world import angle_wrap, yaw_of

W_SMOOTH = 50.0


def grasp_yaw(geo: Geometry, quat: np.ndarray, current: float, max_open: float,
              pos: np.ndarray | None = None, avoid: list[np.ndarray] | None = None) -> tuple[float, float]:
    """(hand yaw, width across the pinch) to pinch a lying box across a horizontal side that fits
    the gripper. Yaw is defined modulo pi. With `avoid` (other objects' positions), the side whose
    open fingers come down farthest from them wins; otherwise the one needing the least turn."""
    half = geo.parts[0].half
    obj_yaw = float(yaw_of(quat))
    options = []
    for width, yaw in ((2 * half[1], obj_yaw), (2 * half[0], obj_yaw + math.pi / 2)):
        if width < max_open - 0.015:
            turn = float(yaw_error(np.array(current), yaw))
            clearance = 0.0
            if avoid and pos is not None:
                across = np.array([-math.sin(yaw), math.cos(yaw)])
                reach = width / 2 + 0.03
                fingers = [pos[:2] + s * reach * across for s in (-1, 1)]
                clearance = min(float(np.linalg.norm(f - a[:2])) for f in fingers for a in avoid)
            options.append((-round(clearance, 3), abs(turn), current - turn, width))
    if not options:
        raise ConfigError("no side of the box fits the gripper; raise effector.max_opening_m")
    _, _, yaw, width = min(options)
    return float(angle_wrap(yaw)), width


def hold_tcp(target: np.ndarray, yaw: float | None = None, w_pos: float = 10.0,
             extra: Callable[[View], np.ndarray] | None = None) -> Callable[[View], np.ndarray]:
    """Cost: bring the TCP to a fixed world point (and the hand to a yaw), smoothly."""

    def cost(v: View) -> np.ndarray:
        run = w_pos * norm(v.tcp - target) + W_SMOOTH * smoothness(v)
        if yaw is not None:
            run = run + 1.0 * yaw_error(v.yaw, yaw) ** 2
        out = total(run)
        return out + extra(v) if extra is not None else out

    return cost


def near(obs: Observation, target: np.ndarray, tol: float, yaw: float | None = None, yaw_tol: float = 0.08) -> bool:
    ok = bool(np.linalg.norm(obs.ee[:3] - target) < tol)
    if yaw is not None:
        ok &= abs(float(yaw_error(np.array(obs.ee[3]), yaw))) < yaw_tol
    return ok


def settle(name: str, seconds: float, grip: float | None) -> StageFactory:
    """Hold where the hand is for `seconds` (the end of an attempt, letting the world come to rest)."""

    def make(obs: Observation) -> Stage:
        here = obs.ee[:3].copy()
        return Stage(name=name, cost=hold_tcp(here, float(obs.ee[3])), done=lambda o: True, hold_s=seconds,
                     grip=grip, goal={"hold_s": seconds})

    return make


def max_open(ctx: ContactContext) -> float:
    return ctx.cfg.effector.max_opening_m
