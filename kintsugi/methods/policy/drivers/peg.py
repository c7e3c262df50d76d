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

from kintsugi.core.errors import KintsugiError
from kintsugi.methods.policy.drivers.base import F64, INF, ND, Driver, Feature

LOW = np.array([-0.15, -0.05, -math.radians(45.0)])
HIGH = np.array([0.15, 0.30, math.radians(45.0)])
(Y_LO, Z_LO, R_LO), (Y_HI, Z_HI, R_HI) = LOW.tolist(), HIGH.tolist()
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
        self._reach_lin, self._reach_rot = self._v_lin * SLACK, self._v_rot * SLACK
        mocap = self.world._mocap
        self._mpos, self._mquat = self.world.data.mocap_pos[mocap], self.world.data.mocap_quat[mocap]
        """Views of the wrist base's commanded pose (what `world.base_pose` reads), read as floats each step."""
        self._mp, self._mq = memoryview(self._mpos), memoryview(self._mquat)
        """The same as flat memoryviews: an item read or write through one costs half a numpy index."""
        self._qp, self._qz = memoryview(self.world.data.qpos), int(self.world._qz)
        self._z_rest, self._z_stiffness = self.world._z_rest, self.world.cfg.wrist.z_stiffness
        """The wrist's z spring: `robot.wrist_force_z()` is (qpos[qz] - rest) x stiffness, read here as floats."""

    @property
    def action_low(self) -> np.ndarray:
        return LOW

    @property
    def action_high(self) -> np.ndarray:
        return HIGH

    def apply(self, action: Any) -> None:
        self._send(action)

    def _send(self, action: Any) -> tuple[float, float, float, float]:
        """Clip the target to the bounds, limit its step to one period's reach, write it to the base's mocap;
        the values written (y, z, the quaternion's w and x). A float64 array of three finite values is read and
        clipped inline (the control rate's common case, the same values `clip_values` gives); anything else (a
        list, another dtype, a wrong length or shape: the unpacking or the sum refuses it) goes through
        `clip_values`, which names the fault."""
        try:
            if type(action) is not ND or action.dtype is not F64:
                raise TypeError
            y1, z1, r1 = action.tolist()
            if not -INF < y1 + z1 + r1 < INF:  # not all finite (a NaN or an infinity makes the sum one)
                raise TypeError
            y1 = Y_LO if y1 < Y_LO else Y_HI if y1 > Y_HI else y1
            z1 = Z_LO if z1 < Z_LO else Z_HI if z1 > Z_HI else z1
            r1 = R_LO if r1 < R_LO else R_HI if r1 > R_HI else r1
        except (TypeError, ValueError):
            y1, z1, r1 = self.clip_values(action)
        p, q = self._mp, self._mq
        y, z, r = p[1], p[2], 2 * math.atan2(q[1], q[0])  # world.base_pose()
        dist = math.hypot(y1 - y, z1 - z)
        if dist > self._reach_lin:
            y1, z1 = y + (y1 - y) * self._v_lin / dist, z + (z1 - z) * self._v_lin / dist
        if abs(r1 - r) > self._reach_rot:
            r1 = r + math.copysign(self._v_rot, r1 - r)
        # world.set_base((y1, z1, r1)), written item by item; the base's x and the quaternion's y and z parts
        # stay the 0.0 every set_base writes (the base moves in the y-z plane and rolls about x)
        p[1] = y1
        p[2] = z1
        q[0] = qw = math.cos(r1 / 2)
        q[1] = qx = math.sin(r1 / 2)
        return y1, z1, qw, qx

    def advance(self, action: Any, images: bool = True) -> tuple[dict[str, np.ndarray] | None, str | None]:
        """`apply`, `tick`, `observe` with the base pose observed from the floats `apply` wrote: the physics
        step leaves the mocap alone, so they are the values `world.base_pose()` reads back after the tick."""
        y, z, qw, qx = self._send(action)
        try:
            self.tick()
        except KintsugiError as exc:
            return None, f"{type(exc).__name__}: {exc}"
        return self._observation(y, z, 2 * math.atan2(qx, qw), images), None

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
        p, q = self._mp, self._mq
        return self._observation(p[1], p[2], 2 * math.atan2(q[1], q[0]), images)

    def _observation(self, y: float, z: float, roll: float, images: bool) -> dict[str, np.ndarray]:
        """The observation of base pose (y, z, roll) with `robot.wrist_force_z()` read as a float from the
        MjData buffer, in two new arrays."""
        force = np.empty(1)  # for one value, an empty array and an item write cost less than numpy.array
        force[0] = (self._qp[self._qz] - self._z_rest) * self._z_stiffness
        obs = {"base_pose": np.array((y, z, roll)), "wrist_force": force}
        if images:
            obs["image"] = self.world.render()
        return obs

    def render(self) -> np.ndarray:
        return self.world.render()
