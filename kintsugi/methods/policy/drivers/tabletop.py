"""System B's step-level API: both arms' joint position targets and grippers at the 100 Hz control rate.

Action (14 values): per arm (left, then right) the six joint position targets (rad, within the joint
limits) and the gripper's closing command in [0, 1] (0 open, 1 closed with the force-limited squeeze; a
value between is a partial closing travel, as a gentle grasp ramps it).

Observation: per arm `<arm>_joint_pos` (6, rad), `<arm>_eef_pos` (3, m), `<arm>_eef_quat` (4, x y z w,
hemisphere-continuous), `<arm>_gripper_opening` (1, m), `<arm>_pad_force` (1, N, the finger pads' normal
force); with images, `image_top` and `image_front` (H, W, 3) uint8; with `perceived=True`, per object
`<object>_centroid` (3, m), `<object>_axis` (3, unit) and `<object>_visible` (1: 1.0 seen, 0.0 not, then zeros)
from the robot's own perception of its camera renders (the features the methods get).

Disturbances that strike "during an atomic action" (drop, shift, knock) are told of action starts through
the task's hook; a policy has no atomic actions, so the driver marks one every `period_s` of control
(planned length `period_s`, both arms), or at the instants of a given `schedule` (a replayed trial's own
action starts, so the replay meets the draws its source met).
"""

from __future__ import annotations

from typing import Any, Callable

import mujoco
import numpy as np

from kintsugi.methods.policy.drivers.base import Driver, Feature
from kintsugi.worlds.tabletop.arm_model import JOINTS
from kintsugi.worlds.tabletop.config import ARMS
from kintsugi.worlds.tabletop.scene import CAMERAS

ACTION_NAMES = tuple(n for arm in ARMS for n in (*(f"{arm}_{j}" for j in JOINTS), f"{arm}_gripper"))
ActionMark = tuple[int, float, tuple[str, ...]]
"""(control step at which an action starts, its planned length s, its arms)."""


class TabletopDriver(Driver):
    family = "tabletop"
    action_names = ACTION_NAMES
    action_unit = "rad (joint targets), 0..1 (gripper closing command)"

    def __init__(self, robot: Any, period_s: float = 2.0, schedule: list[ActionMark] | None = None,
                 perceived: bool = False) -> None:
        super().__init__()
        self.perceived = perceived
        self.robot = robot
        self.world = robot._world  # actuators and sensors only; ground truth stays with the scorer
        self.cfg = self.world.cfg
        self.control_hz = 1.0 / self.cfg.sim.control_dt_s
        self._hook = robot._hook
        self._period = max(1, round(period_s * self.control_hz))
        self._schedule: dict[int, list[tuple[float, tuple[str, ...]]]] | None = None
        if schedule is not None:
            self._schedule = {}
            for step, planned, arms in schedule:
                self._schedule.setdefault(int(step), []).append((float(planned), tuple(arms)))
        self.period_s = period_s
        m = self.world.model
        lows, highs = [], []
        for arm in ARMS:
            rng = m.actuator_ctrlrange[self.world.arms[arm].act]
            lows += [*rng[:, 0], 0.0]
            highs += [*rng[:, 1], 1.0]
        self._low, self._high = np.array(lows), np.array(highs)
        self._full = self.cfg.robot.gripper_max_opening_m

    @property
    def action_low(self) -> np.ndarray:
        return self._low

    @property
    def action_high(self) -> np.ndarray:
        return self._high

    def apply(self, action: Any) -> None:
        a = self.clip(action)
        for i, arm in enumerate(ARMS):
            part = a[7 * i:7 * i + 7]
            self.world.set_joint_targets(arm, part[:6])
            self.world.set_grip_travel(arm, float(part[6]) * self._full)

    def command(self) -> np.ndarray:
        out: list[float] = []
        for arm in ARMS:
            out.extend(self.world.joint_targets(arm))
            out.append(self.world._grip_ctrl[arm] / self._full)
        return np.asarray(out)

    def tick(self) -> None:
        if self._hook is not None:
            if self._schedule is not None:
                for planned, arms in self._schedule.get(self.steps, ()):
                    self._hook.begin_action(planned, arms)
            elif self.steps % self._period == 0:
                self._hook.begin_action(self.period_s, ARMS)
        self.world.tick()
        self.steps += 1

    def record_ticks(self, on_tick: Callable[[np.ndarray], None]) -> None:
        tick = self.world.tick

        def logged() -> None:
            on_tick(self.command())
            tick()
        self.world.tick = logged

    def record_actions(self, on_mark: Callable[[float, tuple[str, ...]], None]) -> None:
        """Have `on_mark(planned_s, arms)` called at every atomic action's start (before the disturbance hook)."""
        hook = self._hook
        if hook is None:
            return
        begin = hook.begin_action

        def logged(planned_s: float, arms: tuple[str, ...]) -> None:
            on_mark(planned_s, tuple(arms))
            begin(planned_s, arms)
        hook.begin_action = logged

    def features(self, images: bool = True) -> dict[str, Feature]:
        out: dict[str, Feature] = {}
        for arm in ARMS:
            out[f"{arm}_joint_pos"] = Feature((6,), -np.pi, np.pi, "float64", "rad", tuple(JOINTS))
            out[f"{arm}_eef_pos"] = Feature((3,), -2.0, 2.0, "float64", "m", ("x", "y", "z"))
            out[f"{arm}_eef_quat"] = Feature((4,), -1.0, 1.0, "float64", "quaternion", ("qx", "qy", "qz", "qw"))
            out[f"{arm}_gripper_opening"] = Feature((1,), 0.0, 1.0, "float64", "m")
            out[f"{arm}_pad_force"] = Feature((1,), 0.0, np.inf, "float64", "N")
        if self.perceived:
            for name in self.robot.objects:
                out[f"{name}_centroid"] = Feature((3,), -2.0, 2.0, "float64", "m", ("x", "y", "z"))
                out[f"{name}_axis"] = Feature((3,), -1.0, 1.0, "float64", "unit", ("x", "y", "z"))
                out[f"{name}_visible"] = Feature((1,), 0.0, 1.0, "float64", "flag")
        if images:
            c = self.cfg.cameras
            for cam in CAMERAS:
                out[f"image_{cam}"] = Feature((c.height, c.width, 3), 0, 255, "uint8", "rgb", image=True)
        return out

    def observe(self, images: bool = True) -> dict[str, np.ndarray]:
        w = self.world
        obs: dict[str, np.ndarray] = {}
        for arm in ARMS:
            pos, rot = w.tcp_pose(arm)
            obs[f"{arm}_joint_pos"] = w.joint_positions(arm)
            obs[f"{arm}_eef_pos"] = pos
            wxyz = np.empty(4)
            mujoco.mju_mat2Quat(wxyz, rot.reshape(-1))
            obs[f"{arm}_eef_quat"] = self.continuous(arm, wxyz[[1, 2, 3, 0]], 3)
            obs[f"{arm}_gripper_opening"] = np.array([w.gripper_opening(arm)])
            obs[f"{arm}_pad_force"] = np.array([w.pad_contacts(arm)[1]])
        if self.perceived:
            for name, f in self.robot.features().items():
                seen = f.visible and f.centroid is not None
                obs[f"{name}_centroid"] = np.array(f.centroid if seen else (0.0, 0.0, 0.0))
                obs[f"{name}_axis"] = np.array(f.axis if seen and f.axis is not None else (0.0, 0.0, 0.0))
                obs[f"{name}_visible"] = np.array([1.0 if seen else 0.0])
        if images:
            for cam in CAMERAS:
                obs[f"image_{cam}"] = w.render(cam)
        return obs

    def render(self) -> np.ndarray:
        return np.hstack([self.world.render(c) for c in CAMERAS])
