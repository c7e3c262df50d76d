"""Executing motion programs: joint-space interpolation to IK solutions, position-controlled.

A program is a list of steps per arm (`Move` through joint waypoints, `Grip`).
`run_programs` advances every arm's program on one clock, so a `drive` moves both
arms simultaneously. A move follows its waypoints at a bounded peak joint speed with
a smooth (cubic) time scaling, then waits until the arm has settled or times out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from kintsugi.worlds.tabletop.config import MotionSection
from kintsugi.worlds.tabletop.world import TabletopWorld

SETTLE_SPEED = 0.03  # rad/s: below this on every joint, a finished move has settled
FINGER_STILL = 0.004  # m/s: the fingers have stopped (on the object or at their end)


@dataclass
class Move:
    """Follow joint waypoints (each an IK solution); `tcp` is the pose the last one should reach."""

    waypoints: list[np.ndarray]
    min_duration_s: float = 0.0
    tcp: tuple[np.ndarray, np.ndarray] | None = None
    label: str = ""


@dataclass
class Grip:
    closed: bool
    label: str = ""
    ramp_s: float = 0.0
    """Closing only: bring the fingers' commanded travel from where they are to closed over this long (the
    paper's close_gripper sample_num), instead of at once: the squeeze builds up instead of the pads striking
    (a thin utensil struck by both pads at once can pop up and roll onto its side)."""


Step = Move | Grip


@dataclass
class StepReport:
    label: str
    pos_err_m: float = 0.0
    rot_err_deg: float = 0.0
    settled: bool = True


@dataclass
class _Cursor:
    steps: list[Step]
    index: int = 0
    t0: float = 0.0
    path: np.ndarray | None = None  # (n, 6) waypoints including the start
    knots: np.ndarray | None = None  # cumulative joint-space length per waypoint
    duration: float = 0.0
    end_time: float | None = None
    reports: list[StepReport] = field(default_factory=list)
    travel0: float = 0.0  # a gentle close starts from this commanded travel

    @property
    def done(self) -> bool:
        return self.index >= len(self.steps)


def planned_duration(steps: list[Step], start: np.ndarray, motion: MotionSection) -> float:
    """Nominal time a program takes (used to place a disturbance at a random instant of it)."""
    total, q = 0.0, start
    for s in steps:
        if isinstance(s, Move):
            path = np.vstack([q, *s.waypoints])
            total += _duration(path, s.min_duration_s, motion)
            q = s.waypoints[-1]
        else:
            total += motion.gripper_time_s / 2 + (s.ramp_s if s.closed else 0.0)
    return total


def _duration(path: np.ndarray, min_duration: float, motion: MotionSection) -> float:
    length = float(np.abs(np.diff(path, axis=0)).max(axis=1).sum()) if len(path) > 1 else 0.0
    # A cubic time scaling peaks at 1.5x the mean speed.
    return max(1.5 * length / np.radians(motion.joint_speed_deg_s), min_duration, 0.05)


def _interp(c: _Cursor, s: float) -> np.ndarray:
    assert c.path is not None and c.knots is not None
    d = s * c.knots[-1]
    i = int(np.clip(np.searchsorted(c.knots, d, side="right") - 1, 0, len(c.path) - 2))
    span = c.knots[i + 1] - c.knots[i]
    a = 0.0 if span <= 0 else (d - c.knots[i]) / span
    return c.path[i] + np.clip(a, 0.0, 1.0) * (c.path[i + 1] - c.path[i])


def run_programs(world: TabletopWorld, programs: dict[str, list[Step]], motion: MotionSection,
                 on_tick: Callable[[], None] | None = None,
                 stop: Callable[[], bool] | None = None) -> dict[str, list[StepReport]]:
    """Run each arm's steps until all arms finish, or until `stop()` (asked after every control tick)
    says to stop: then the arms hold their last joint targets and unfinished steps have no report.
    Returns one report per finished step and arm."""
    cursors = {arm: _Cursor(list(steps)) for arm, steps in programs.items()}
    for arm, c in cursors.items():
        _start(world, arm, c, motion)
    while not all(c.done for c in cursors.values()):
        world.tick()
        if on_tick is not None:
            on_tick()
        if stop is not None and stop():
            break
        t = float(world.data.time)
        for arm, c in cursors.items():
            if c.done:
                continue
            if _advance(world, arm, c, t, motion):
                c.index += 1
                _start(world, arm, c, motion)
    return {arm: c.reports for arm, c in cursors.items()}


def _start(world: TabletopWorld, arm: str, c: _Cursor, motion: MotionSection) -> None:
    while not c.done:
        step = c.steps[c.index]
        c.t0 = float(world.data.time)
        c.end_time = None
        if isinstance(step, Grip):
            if step.closed and step.ramp_s > 0.0:
                c.travel0 = world.cfg.robot.gripper_max_opening_m - world.gripper_opening(arm)
                world.set_grip_travel(arm, c.travel0)
            else:
                world.set_grip(arm, step.closed)
            return
        c.path = np.vstack([world.joint_targets(arm), *step.waypoints])
        seg = np.abs(np.diff(c.path, axis=0)).max(axis=1)
        c.knots = np.concatenate([[0.0], np.cumsum(seg)])
        c.duration = _duration(c.path, step.min_duration_s, motion)
        return


def _advance(world: TabletopWorld, arm: str, c: _Cursor, t: float, motion: MotionSection) -> bool:
    """Command the current step at time t; True when it is finished."""
    step = c.steps[c.index]
    elapsed = t - c.t0
    if isinstance(step, Grip):
        ramp = step.ramp_s if step.closed else 0.0
        if ramp > 0.0:
            full = world.cfg.robot.gripper_max_opening_m
            world.set_grip_travel(arm, c.travel0 + (full - c.travel0) * min(elapsed / ramp, 1.0))
            elapsed -= ramp
            if elapsed < 0.0:
                return False
        still = world.finger_speed(arm) < FINGER_STILL
        if (elapsed >= 0.08 and still) or elapsed >= motion.gripper_time_s:
            c.reports.append(StepReport(label=step.label or ("close" if step.closed else "open")))
            return True
        return False
    tau = min(elapsed / c.duration, 1.0)
    world.set_joint_targets(arm, _interp(c, tau * tau * (3.0 - 2.0 * tau)))
    if tau < 1.0:
        return False
    if c.end_time is None:
        c.end_time = t
    settled = float(np.abs(world.joint_velocities(arm)).max()) < SETTLE_SPEED
    if not settled and t - c.end_time < motion.settle_timeout_s:
        return False
    report = StepReport(label=step.label, settled=settled)
    if step.tcp is not None:
        pos, rot = world.tcp_pose(arm)
        report.pos_err_m = float(np.linalg.norm(pos - step.tcp[0]))
        r = step.tcp[1].T @ rot
        report.rot_err_deg = float(np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0))))
    c.reports.append(report)
    return True
