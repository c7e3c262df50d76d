"""System C's step-level API: the force-limited end effector's five servo targets at the robot's inner
rate (100 Hz, the rate every method's commands reach the servos at).

Action (5 values): `x`, `y`, `z` (m, fingertip height), `yaw` (rad) and the finger `opening` (m) targets,
within the actuators' control ranges; the servos' force limits make any target a bounded push.

Observation: `ee` (x, y, z, yaw), `ee_vel`, `fingers` (2 joint positions, m), `finger_vel`, `force`
(3, N: the tared wrist F/T force the hand exerts, world frame), `torque` (3, N m, hand frame), `touch`
(2, N: the finger pads), and per object `<name>_pos` (3, m), `<name>_quat` (4, w x y z,
hemisphere-continuous), `<name>_lin_vel`, `<name>_ang_vel` from the robot's pose tracker (it stands for
FoundationPose / motion capture: poses, never masses or frictions); with images, `image` (H, W, 3) uint8.

`restart()` puts the scene back as an experimenter would between attempts (the robot's own `restart`).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from kintsugi.methods.policy.drivers.base import Driver, DriverError, Feature

ACTION_NAMES = ("x", "y", "z", "yaw", "opening")


class ContactDriver(Driver):
    family = "contact"
    action_names = ACTION_NAMES
    action_unit = "m, m, m, rad, m"

    def __init__(self, robot: Any) -> None:
        super().__init__()
        self.robot = robot
        self.world = robot._world  # actuators and sensors only; ground truth stays with the scorer
        self._n_sub = robot._steps_per_tick
        self.control_hz = 1.0 / robot.inner_dt
        rng = robot.ctrlrange
        if len(rng) != len(ACTION_NAMES):
            raise DriverError(f"the contact effector has {len(rng)} actuators, the driver knows {len(ACTION_NAMES)}")
        self._low, self._high = rng[:, 0].copy(), rng[:, 1].copy()
        self.objects = tuple(self.world.layout.objects)
        lay = self.world.layout
        self._qidx = np.concatenate([lay.ee_qpos, lay.finger_qpos,
                                     *(np.arange(lay.obj_qpos[k], lay.obj_qpos[k] + 7) for k in self.objects)])
        self._vidx = np.concatenate([lay.ee_dof, lay.finger_dof,
                                     *(np.arange(lay.obj_dof[k], lay.obj_dof[k] + 6) for k in self.objects)])
        s = lay.sensors
        self._sidx = np.concatenate([np.arange(s[k].start, s[k].stop) for k in ("ft_force", "ft_torque")]
                                    + [[s["touch_l"].start, s["touch_r"].start]])
        self._hand_weight = lay.hand_weight_n
        d = self.world.data
        self._ctrl, self._qpos, self._qvel, self._sens = d.ctrl, d.qpos, d.qvel, d.sensordata
        """Index arrays resolved once (what `robot.observe` reads): one gather per source each step."""

    @property
    def action_low(self) -> np.ndarray:
        return self._low

    @property
    def action_high(self) -> np.ndarray:
        return self._high

    def apply(self, action: Any) -> None:
        self._ctrl[:] = self.clip_values(action)

    def command(self) -> np.ndarray:
        return self.world.data.ctrl.copy()

    def tick(self) -> None:
        self.world.step(self._n_sub)
        for watch in self.robot._watchers:
            watch(self.world)
        self.steps += 1

    def restart(self) -> None:
        self.robot.restart()

    def record_ticks(self, on_tick: Callable[[np.ndarray], None]) -> None:
        step = self.world.step

        def logged(n: int = 1) -> None:
            if n != self._n_sub:
                raise DriverError(f"the contact world stepped {n} physics steps at once, not one inner period "
                                  f"({self._n_sub}): the recording cannot be replayed step by step")
            on_tick(self.command())
            step(n)
        self.world.step = logged

    def record_restarts(self, on_restart: Callable[[], None]) -> None:
        restart = self.robot.restart

        def logged() -> Any:
            on_restart()
            return restart()
        self.robot.restart = logged

    def features(self, images: bool = True) -> dict[str, Feature]:
        f = {"ee": Feature((4,), -np.inf, np.inf, "float64", "m, m, m, rad", ("x", "y", "z", "yaw")),
             "ee_vel": Feature((4,), -np.inf, np.inf, "float64", "m/s, rad/s", ("x", "y", "z", "yaw")),
             "fingers": Feature((2,), -np.inf, np.inf, "float64", "m", ("left", "right")),
             "finger_vel": Feature((2,), -np.inf, np.inf, "float64", "m/s", ("left", "right")),
             "force": Feature((3,), -np.inf, np.inf, "float64", "N", ("fx", "fy", "fz")),
             "torque": Feature((3,), -np.inf, np.inf, "float64", "N m", ("tx", "ty", "tz")),
             "touch": Feature((2,), 0.0, np.inf, "float64", "N", ("left", "right"))}
        for name in self.objects:
            f[f"{name}_pos"] = Feature((3,), -np.inf, np.inf, "float64", "m", ("x", "y", "z"))
            f[f"{name}_quat"] = Feature((4,), -1.0, 1.0, "float64", "quaternion", ("qw", "qx", "qy", "qz"))
            f[f"{name}_lin_vel"] = Feature((3,), -np.inf, np.inf, "float64", "m/s", ("x", "y", "z"))
            f[f"{name}_ang_vel"] = Feature((3,), -np.inf, np.inf, "float64", "rad/s", ("x", "y", "z"))
        if images:
            c = self.world.cfg.camera
            f["image"] = Feature((c.height, c.width, 3), 0, 255, "uint8", "rgb", image=True)
        return f

    def observe(self, images: bool = True) -> dict[str, np.ndarray]:
        """What `robot.observe()` gives (proprioception, the tared wrist force, the pads, the pose tracker's
        objects), read with index arrays resolved once: one gather per source, entries are views of it."""
        q, v, sens = self._qpos[self._qidx], self._qvel[self._vidx], self._sens[self._sidx]
        yaw = q[3]
        c, s = np.cos(yaw), np.sin(yaw)
        rx, ry, rz = sens[0], sens[1], sens[2]  # tared_force_world: the hand frame's pull, rotated to the world
        out = {"ee": q[0:4], "ee_vel": v[0:4], "fingers": q[4:6], "finger_vel": v[4:6],
               "force": np.array([c * rx - s * ry, s * rx + c * ry, rz - self._hand_weight]),
               "torque": sens[3:6], "touch": sens[6:8]}
        for k, name in enumerate(self.objects):
            a, b = 6 + 7 * k, 6 + 6 * k
            out[f"{name}_pos"] = q[a:a + 3]
            out[f"{name}_quat"] = np.array(self.continuous_values(name, q[a + 3:a + 7].tolist(), 0))
            out[f"{name}_lin_vel"] = v[b:b + 3]
            out[f"{name}_ang_vel"] = v[b + 3:b + 6]
        if images:
            out["image"] = self.render()
        return out

    def render(self) -> np.ndarray:
        r = self.world.renderer()
        r.update_scene(self.world.data, camera="scene")
        return r.render().copy()
