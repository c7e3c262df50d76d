"""Inverse kinematics per arm with mink, on a separate kinematic model (no objects, no gripper).

A target is the tool centre point's position and rotation in the world frame. It is
clipped to the configured workspace box first (as in the paper), then solved by
iterated differential IK (a QP with joint limits, solved by daqp), from the current
joints and, if that stalls, from home. A residual above tolerance is a real failure:
joint limits and link lengths decide what is reachable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mink
import mujoco
import numpy as np

from kintsugi.worlds.tabletop.arm_model import kinematic_xml
from kintsugi.worlds.tabletop.config import MotionSection, RobotSection

MAX_STEP_RAD = 0.8
"""Largest joint change per IK iteration (keeps Gauss-Newton steps inside the linear regime)."""


@dataclass(frozen=True)
class IKResult:
    q: np.ndarray
    ok: bool
    pos_err_m: float
    rot_err_deg: float
    clipped: bool
    target_pos: np.ndarray
    """The target actually solved for (after workspace clipping)."""
    iterations: int

    def message(self) -> str:
        what = "reached" if self.ok else "unreachable"
        return (f"IK {what}: residual {self.pos_err_m * 1000:.1f} mm, {self.rot_err_deg:.1f} deg"
                + (" (target clipped to the workspace)" if self.clipped else ""))


class ArmIK:
    """IK for one arm. Not thread-safe: it owns one mink configuration."""

    def __init__(self, robot: RobotSection, motion: MotionSection, arm: str) -> None:
        self.arm = arm
        self.model = mujoco.MjModel.from_xml_string(kinematic_xml(robot, arm))
        self.conf = mink.Configuration(self.model)
        self.site = f"{arm}_tcp"
        self.task = mink.FrameTask(self.site, "site", position_cost=1.0, orientation_cost=0.3, lm_damping=1e-4)
        self.limits = [mink.ConfigurationLimit(self.model, gain=0.9)]
        self.home = np.radians(robot.home_deg)
        self.lower = self.model.jnt_range[:, 0].copy()
        self.upper = self.model.jnt_range[:, 1].copy()
        self.box = np.array([motion.workspace_x_m, motion.workspace_y_m, motion.workspace_z_m])
        self.pos_tol = motion.ik_pos_tol_m
        self.rot_tol = math.radians(motion.ik_rot_tol_deg)
        self.max_iters = motion.ik_max_iters
        self._site_id = self.model.site(self.site).id

    def fk(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tool centre point position and rotation for joint angles q."""
        self.conf.update(q)
        d = self.conf.data
        return d.site_xpos[self._site_id].copy(), d.site_xmat[self._site_id].reshape(3, 3).copy()

    def clip(self, pos: np.ndarray) -> tuple[np.ndarray, bool]:
        clipped = np.clip(pos, self.box[:, 0], self.box[:, 1])
        return clipped, bool(np.any(np.abs(clipped - pos) > 1e-9))

    def solve(self, pos: np.ndarray, rot: np.ndarray, seed: np.ndarray) -> IKResult:
        """Joint angles putting the tool centre point at (pos, rot); `ok` says whether it got there."""
        target, clipped = self.clip(np.asarray(pos, float))
        self.task.set_target(mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(np.asarray(rot)), target))
        best: tuple[float, np.ndarray, float, float, int] | None = None
        for start in (np.clip(seed, self.lower, self.upper), self.home):
            q, pe, re, it = self._iterate(start, target, np.asarray(rot, float))
            score = pe + 0.1 * re
            if best is None or score < best[0]:
                best = (score, q, pe, re, it)
            if pe <= self.pos_tol and re <= self.rot_tol:
                break
        _, q, pe, re, it = best
        return IKResult(q=q, ok=bool(pe <= self.pos_tol and re <= self.rot_tol), pos_err_m=pe,
                        rot_err_deg=math.degrees(re), clipped=clipped, target_pos=target, iterations=it)

    def _errors(self, target: np.ndarray, rot: np.ndarray) -> tuple[float, float]:
        """Position error (m) and rotation angle error (rad) of the current configuration."""
        d = self.conf.data
        pe = float(np.linalg.norm(d.site_xpos[self._site_id] - target))
        r = rot.T @ d.site_xmat[self._site_id].reshape(3, 3)
        re = math.acos(float(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)))
        return pe, re

    def _iterate(self, start: np.ndarray, target: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, float, float, int]:
        self.conf.update(start.copy())
        for it in range(self.max_iters):
            pe, re = self._errors(target, rot)
            if pe <= self.pos_tol * 0.2 and re <= self.rot_tol * 0.2:
                return self.conf.q.copy(), pe, re, it
            try:
                v = mink.solve_ik(self.conf, [self.task], 1.0, "daqp", damping=1e-6, limits=self.limits)
            except mink.NoSolutionFound:
                break
            peak = float(np.abs(v).max())
            if peak > MAX_STEP_RAD:
                v *= MAX_STEP_RAD / peak
            if peak < 1e-7:
                break  # stalled at a limit or a singularity
            self.conf.integrate_inplace(v, 1.0)
        pe, re = self._errors(target, rot)
        return self.conf.q.copy(), pe, re, self.max_iters
