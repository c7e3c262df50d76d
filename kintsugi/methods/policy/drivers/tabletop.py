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

from itertools import chain
from typing import Any, Callable

import mujoco
import numpy as np

from kintsugi.methods.policy.drivers.base import Driver, Feature, scatter
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
        ids = [self.world.arms[arm] for arm in ARMS]
        d = self.world.data
        self._data, self._model = d, m
        self._ctrl, self._qpos, self._xpos, self._xmat = d.ctrl, d.qpos, d.site_xpos, d.site_xmat
        """Views of the MjData buffers (fixed for the world's life), without a binding call per read."""
        self._cm, self._qp = memoryview(d.ctrl), memoryview(d.qpos)
        """The actuators' targets and the joint positions as flat memoryviews, for items written or read as floats."""
        n = len(JOINTS) + 1  # one arm's action values: its joints, then its gripper
        joints = tuple((n * k + j, int(a)) for k, i in enumerate(ids) for j, a in enumerate(i.act))
        self._pairs = joints
        self._grip_ctrl = [(arm, n * k + n - 1, int(i.grip_act)) for k, (arm, i) in enumerate(zip(ARMS, ids))]
        """Writes every joint target (action index -> actuator); (arm, action index, actuator) of every gripper."""
        idx = np.intp  # the index type numpy gathers with, so that no gather casts its index first
        xpos = d.site_xpos.reshape(-1)  # a flat view: a site's position is three consecutive entries
        self._arms = [(arm, f"{arm}_joint_pos", f"{arm}_eef_pos", f"{arm}_eef_quat", f"{arm}_gripper_opening",
                       f"{arm}_pad_force", i.qpos.astype(idx), xpos, np.arange(3 * i.tcp, 3 * i.tcp + 3, dtype=idx),
                       d.site_xmat[int(i.tcp)], int(i.finger_qpos[0]), int(i.finger_qpos[1]))
                      for arm, i in zip(ARMS, ids)]
        """Per arm: its name, its entries' keys, its joints' qpos (a gather), its tool site's position (a gather
        from the flat positions) and rotation matrix (a view), its two fingers' qpos."""
        self._wxyz = np.empty(4)
        self._xyzw = np.array([1, 2, 3, 0], dtype=idx)
        """The tool's quaternion as `mju_mat2Quat` writes it (w, x, y, z), and the gather to x, y, z, w."""
        self._pads = {g: k for k, i in enumerate(ids) for g in i.pads}
        self._force = np.zeros(6)
        self._contacts = d.contact
        """Pad geoms -> arm; `mj_contactForce`'s output; the contact list's binding, made once (it reads the
        current contacts at each access, as `data.contact` would give them)."""

    @property
    def action_low(self) -> np.ndarray:
        return self._low

    @property
    def action_high(self) -> np.ndarray:
        return self._high

    def apply(self, action: Any) -> None:
        """`world.set_joint_targets` and `world.set_grip_travel` for both arms, written item by item to the
        actuators' targets (the gripper's travel is its command in [0, 1] x the full opening, so within the range
        `set_grip_travel` clamps to; a gripper the world holds open keeps its target until it lets go)."""
        a = self.clip_values(action)
        cm = self._cm
        scatter(cm, a, self._pairs)
        w = self.world
        grip, forced, full = w._grip_ctrl, w._forced_open, self._full
        for arm, i, k in self._grip_ctrl:
            grip[arm] = travel = a[i] * full
            if arm not in forced:
                cm[k] = travel

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
        """The sensors as the world's own readers give them (`joint_positions`, `tcp_pose`, `gripper_opening`,
        `pad_contacts`' force), read with index arrays resolved once: every array entry is one gather from its
        MjData array (which makes the entry's own fresh array, the cheapest way numpy makes one)."""
        w = self.world
        qpos, qp, wxyz, full, xyzw, last = self._qpos, self._qp, self._wxyz, self._full, self._xyzw, self._last_quat
        forces = self.pad_forces()
        obs: dict[str, np.ndarray] = {}
        for k, (arm, kj, kp, kq, ko, kf, joints, xpos, site, xmat, f0, f1) in enumerate(self._arms):
            obs[kj] = qpos[joints]
            obs[kp] = xpos[site]
            mujoco.mju_mat2Quat(wxyz, xmat)
            obs[kq] = quat = wxyz[xyzw]
            qw, qx, qy, qz = wxyz.tolist()  # hemisphere-continuous: `continuous_values(arm, [x, y, z, w], 3)`
            ref = last.get(arm)
            if (qw < 0) if ref is None else (qx * ref[0] + qy * ref[1] + qz * ref[2] + qw * ref[3] < 0):
                quat *= -1.0
                last[arm] = [-qx, -qy, -qz, -qw]
            else:
                last[arm] = [qx, qy, qz, qw]
            obs[ko] = opening = np.empty(1)
            opening[0] = full - (qp[f0] + qp[f1])  # world.gripper_opening
            obs[kf] = force = np.empty(1)
            force[0] = forces[k]
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

    def pad_forces(self) -> list[float]:
        """Per arm the total normal force on its finger pads (N), summed over contacts in the same order as
        `world.pad_contacts(arm)[1]`; only the contacts that touch a pad are visited."""
        d = self._data
        out = [0.0] * len(ARMS)
        if d.ncon == 0:
            return out
        pads, buf, m = self._pads, self._force, self._model
        geoms = self._contacts.geom.tolist()
        if pads.keys().isdisjoint(chain.from_iterable(geoms)):  # no pad touches anything
            return out
        force = mujoco.mj_contactForce
        for i, (a, b) in enumerate(geoms):
            ka, kb = pads.get(a), pads.get(b)
            if ka is None and kb is None:
                continue
            force(m, d, i, buf)
            f = abs(buf.item(0))
            if ka is None:
                out[kb] += f
            else:
                out[ka] += f
                if kb is not None and kb != ka:  # the two arms' pads touching each other
                    out[kb] += f
        return out

    def render(self) -> np.ndarray:
        return np.hstack([self.world.render(c) for c in CAMERAS])
