"""System A's step-level API: the soft wrist's base pose at the skills' control rate (250 Hz).

Action (3 values): the wrist base target `y`, `z` (m) and `roll` (rad), in the planar workspace's bounds.
Each control period the base moves toward it at most as fast as the skills move it (`control.speed_mm_s`,
`control.rot_speed_deg_s`): a target within one period's reach is taken exactly, a farther one is
approached along the straight line.

Observation: `base_pose` (y, z m; roll rad, the base's commanded pose as its encoders report it),
`wrist_force` (1, N, the tared F/T sensor's z force: positive when the spring is compressed); with
images, `image` (H, W, 3) uint8 from the fixed camera viewing the y-z plane.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from kintsugi.methods.policy.drivers.base import Driver, Feature

LOW = np.array([-0.15, -0.05, -math.radians(45.0)])
HIGH = np.array([0.15, 0.30, math.radians(45.0)])
SLACK = 1.0 + 1e-9
"""A target this close to one period's reach is taken exactly (the skills' own steps land on their goal)."""


class PegDriver(Driver):
    family = "peg"
    action_names = ("base_y", "base_z", "base_roll")
    action_unit = "m, m, rad"

    def __init__(self, robot: Any) -> None:
        super().__init__()
        self.robot = robot
        self.world = robot._world  # actuators and sensors only; ground truth stays with the scorer
        ctl = self.world.cfg.control
        self._n_sub = max(1, round(1.0 / ctl.rate_hz / self.world.model.opt.timestep))
        dt = self._n_sub * self.world.model.opt.timestep
        self.control_hz = 1.0 / dt
        self._v_lin = ctl.speed_mm_s * 1e-3 * dt
        self._v_rot = math.radians(ctl.rot_speed_deg_s) * dt
        mocap = self.world._mocap
        self._mpos, self._mquat = self.world.data.mocap_pos[mocap], self.world.data.mocap_quat[mocap]
        """Views of the wrist base's commanded pose (what `world.base_pose` reads), read as floats each step."""

    @property
    def action_low(self) -> np.ndarray:
        return LOW

    @property
    def action_high(self) -> np.ndarray:
        return HIGH

    def apply(self, action: Any) -> None:
        y1, z1, r1 = self.clip_values(action)
        y, z, r = self._pose()
        dist = math.hypot(y1 - y, z1 - z)
        if dist > self._v_lin * SLACK:
            y1, z1 = y + (y1 - y) * self._v_lin / dist, z + (z1 - z) * self._v_lin / dist
        if abs(r1 - r) > self._v_rot * SLACK:
            r1 = r + math.copysign(self._v_rot, r1 - r)
        p, q = self._mpos, self._mquat  # world.set_base((y1, z1, r1)), written item by item to its views
        p[0], p[1], p[2] = 0.0, y1, z1
        q[0], q[1], q[2], q[3] = math.cos(r1 / 2), math.sin(r1 / 2), 0.0, 0.0

    def _pose(self) -> tuple[float, float, float]:
        """`world.base_pose()` as floats, without building an array."""
        _, y, z = self._mpos.tolist()
        qw, qx, _, _ = self._mquat.tolist()
        return y, z, 2 * math.atan2(qx, qw)

    def command(self) -> np.ndarray:
        return self.world.base_pose()

    def tick(self) -> None:
        self.world.step(self._n_sub)
        self.steps += 1

    def record_ticks(self, on_tick: Callable[[np.ndarray], None]) -> None:
        step = self.world.step

        def logged(n: int) -> None:
            if n != self._n_sub:
                from kintsugi.methods.policy.drivers.base import DriverError

                raise DriverError(f"the peg world stepped {n} physics steps at once, not one control period "
                                  f"({self._n_sub}): the recording cannot be replayed step by step")
            on_tick(self.command())
            step(n)
        self.world.step = logged

    def features(self, images: bool = True) -> dict[str, Feature]:
        out = {"base_pose": Feature((3,), -1.0, 1.0, "float64", "m, m, rad", ("y", "z", "roll")),
               "wrist_force": Feature((1,), -np.inf, np.inf, "float64", "N")}
        if images:
            c = self.world.cfg.camera
            out["image"] = Feature((c.height, c.width, 3), 0, 255, "uint8", "rgb", image=True)
        return out

    def observe(self, images: bool = True) -> dict[str, np.ndarray]:
        v = np.array((*self._pose(), self.robot.wrist_force_z()))  # one array, the entries are views of it
        obs = {"base_pose": v[0:3], "wrist_force": v[3:4]}
        if images:
            obs["image"] = self.world.render()
        return obs

    def render(self) -> np.ndarray:
        return self.world.render()
