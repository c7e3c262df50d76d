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

from kintsugi.methods.policy.drivers.base import Driver, DriverError, Feature, scatter

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
        s = lay.sensors
        d = self.world.data
        self._ctrl, self._qpos, self._qvel, self._sens = d.ctrl, d.qpos, d.qvel, d.sensordata
        """Views of the MjData buffers (fixed for the world's life), without a binding call per read."""
        self._cm, self._qp, self._sp = memoryview(d.ctrl), memoryview(d.qpos), memoryview(d.sensordata)
        """The same as flat memoryviews, for the items read or written as floats."""
        self._pairs = tuple((i, i) for i in range(len(ACTION_NAMES)))
        self._yaw, self._hand_weight = int(lay.ee_qpos[3]), lay.hand_weight_n
        self._f = s["ft_force"].start
        idx = np.intp  # the index type numpy gathers with, so that no gather casts its index first
        self._ee, self._ee_vel = lay.ee_qpos.astype(idx), lay.ee_dof.astype(idx)
        self._fingers, self._finger_vel = lay.finger_qpos.astype(idx), lay.finger_dof.astype(idx)
        self._torque = np.arange(s["ft_torque"].start, s["ft_torque"].stop, dtype=idx)
        self._touch = np.array([s["touch_l"].start, s["touch_r"].start], dtype=idx)
        self._tracked = []
        for name in self.objects:
            a, b = int(lay.obj_qpos[name]), int(lay.obj_dof[name])
            self._tracked.append((name, f"{name}_pos", f"{name}_quat", f"{name}_lin_vel", f"{name}_ang_vel",
                                  np.arange(a, a + 3, dtype=idx), np.arange(a + 3, a + 7, dtype=idx),
                                  np.arange(b, b + 3, dtype=idx), np.arange(b + 3, b + 6, dtype=idx)))
        """Index arrays resolved once (what `robot.observe` reads): every entry is one gather from its MjData
        array, which makes the entry's own fresh array (the cheapest way numpy makes one)."""

    @property
    def action_low(self) -> np.ndarray:
        return self._low

    @property
    def action_high(self) -> np.ndarray:
        return self._high

    def apply(self, action: Any) -> None:
        scatter(self._cm, self.clip_values(action), self._pairs)  # world.data.ctrl[:] = the clipped action

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
        objects), read with index arrays resolved once: one gather per entry. The force is
        `tared_force_world`'s arithmetic on floats (numpy's cosine and sine of the yaw, as it takes them)."""
        qpos, qvel, sens, sp, f = self._qpos, self._qvel, self._sens, self._sp, self._f
        rx, ry, rz = sp[f], sp[f + 1], sp[f + 2]
        yaw = self._qp[self._yaw]
        c, s = float(np.cos(yaw)), float(np.sin(yaw))
        out = {"ee": qpos[self._ee], "ee_vel": qvel[self._ee_vel], "fingers": qpos[self._fingers],
               "finger_vel": qvel[self._finger_vel],
               "force": np.array((c * rx - s * ry, s * rx + c * ry, rz - self._hand_weight)),
               "torque": sens[self._torque], "touch": sens[self._touch]}
        last = self._last_quat
        for name, kp, kq, kl, ka, ip, iq, il, ia in self._tracked:
            out[kp] = qpos[ip]
            out[kq] = quat = qpos[iq]
            w, x, y, z = q = quat.tolist()  # hemisphere-continuous: `continuous_values(name, q, 0)`
            ref = last.get(name)
            if (w < 0) if ref is None else (w * ref[0] + x * ref[1] + y * ref[2] + z * ref[3] < 0):
                quat *= -1.0
                q = [-w, -x, -y, -z]
            last[name] = q
            out[kl] = qvel[il]
            out[ka] = qvel[ia]
        if images:
            out["image"] = self.render()
        return out

    def render(self) -> np.ndarray:
        r = self.world.renderer()
        r.update_scene(self.world.data, camera="scene")
        return r.render().copy()
