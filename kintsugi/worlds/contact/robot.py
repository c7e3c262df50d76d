"""The robot as a method sees it: commands to five force-limited servos, its own sensors, and a
pose tracker for the objects. Never the evaluation world's masses, frictions or contacts.

What a method can read:
- proprioception: end-effector x, y, z, yaw, finger positions and their velocities;
- the wrist F/T sensor, tared and in the world frame (`tared_force_world`), and the
  finger touch pads;
- object poses and velocities from the robot's camera (`use_poses("perceived")`: depth and
  segmentation renders fitted with the known models, `kintsugi.worlds.contact.perception`), or from
  `pose_tracker`, the ONE place that reads object state from the simulator: an oracle standing for a
  perfect tracker (a motion-capture system).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import mujoco
import numpy as np

from kintsugi.control.rollout import get_state
from kintsugi.worlds.contact.world import EvaluationWorld, tared_force_world


@dataclass(frozen=True)
class TrackedObject:
    pos: np.ndarray  # (3,) m
    quat: np.ndarray  # (4,) w, x, y, z
    lin_vel: np.ndarray  # (3,) m/s
    ang_vel: np.ndarray  # (3,) rad/s, world frame


@dataclass(frozen=True)
class Observation:
    t: float
    ee: np.ndarray  # x, y, z (fingertip height), yaw
    ee_vel: np.ndarray
    fingers: np.ndarray  # the two finger joint positions (opening = their sum)
    finger_vel: np.ndarray
    force: np.ndarray  # (3,) N: what the hand pushes on its surroundings with, world frame
    torque: np.ndarray  # (3,) N m, hand frame (raw)
    touch: np.ndarray  # (2,) N: left and right pad
    objects: dict[str, TrackedObject]
    ctrl: np.ndarray  # the command in force (nu,)

    @property
    def opening(self) -> float:
        return float(self.fingers.sum())


def pose_tracker(world: EvaluationWorld) -> dict[str, TrackedObject]:
    """What a pose tracker gives: each object's 6-DoF pose and velocity, read from the simulator.

    The paper's simulation uses FoundationPose and its real robot a Vicon system; like
    them, this reports where objects are, never what they weigh or how they slide.
    """
    out = {}
    for name in world.layout.objects:
        pos, quat = world.object_pose(name)
        lin, ang = world.object_velocity(name)
        out[name] = TrackedObject(pos=pos, quat=quat, lin_vel=lin, ang_vel=ang)
    return out


@dataclass
class ExecutionLog:
    """One attempt as the robot recorded it at the inner control rate: the observation before each
    command and the command sent (what system identification gets; no ground truth in it)."""

    obs: list[Observation] = field(default_factory=list)
    ctrl: list[np.ndarray] = field(default_factory=list)

    def add(self, obs: Observation, ctrl: np.ndarray) -> None:
        self.obs.append(obs)
        self.ctrl.append(ctrl.copy())


Feedback = Callable[[Observation, np.ndarray], np.ndarray]
"""(observation, planned action) -> the action to send (Eq. 5's reactive correction)."""
Plan = Callable[[float], np.ndarray]
"""Sim time -> the planned command at that time (MPPI's spline between replans)."""


class ContactRobot:
    """Commands and sensors of the force-limited end effector in the evaluation world."""

    def __init__(self, world: EvaluationWorld, inner_hz: float = 100.0,
                 watchers: list[Callable[[EvaluationWorld], None]] | None = None,
                 on_restart: list[Callable[[], None]] | None = None) -> None:
        self._world = world
        self._initial = get_state(world.model, world.data)
        self._on_restart = on_restart if on_restart is not None else []
        self.attempts = 1
        self.show_plan: Callable[[np.ndarray, np.ndarray], None] | None = None
        """Set by a video recorder: the planner passes it the predicted path and contact candidates."""
        self.plan_stats: Callable[[float, str, float, float, float], None] | None = None
        """Set by a video recorder: the planner passes it (t, stage, lowest cost, temperature, ESS fraction)."""
        self._steps_per_tick = max(1, round(1.0 / (inner_hz * world.model.opt.timestep)))
        self.inner_dt = self._steps_per_tick * world.model.opt.timestep
        self._watchers = watchers if watchers is not None else []
        self.ctrlrange = world.ctrlrange
        self.log = ExecutionLog()
        self._estimator = None
        self.poses = "truth"
        """Where `observe` takes object poses from: "truth" (`pose_tracker`) or "perceived" (the camera)."""

    def use_poses(self, mode: str) -> None:
        """Take object poses from the camera ("perceived": `kintsugi.worlds.contact.perception`) or from the exact
        tracker ("truth", an oracle)."""
        if mode == self.poses:
            return
        if self._estimator is not None:
            self._estimator.close()
            self._estimator = None
        if mode == "perceived":
            from kintsugi.worlds.contact.perception import PoseEstimator

            w = self._world
            self._estimator = PoseEstimator(w.model, w.scene.geometry, w.layout.obj_geoms, w.cfg.perception)
        self.poses = mode

    def _objects(self) -> dict[str, TrackedObject]:
        if self._estimator is None:
            return pose_tracker(self._world)
        return {k: TrackedObject(*v) for k, v in self._estimator.poses(self._world.data).items()}

    @property
    def sim_time(self) -> float:
        return float(self._world.data.time)

    def observe(self) -> Observation:
        w = self._world
        lay, d = w.layout, w.data
        raw_f = d.sensordata[lay.sensors["ft_force"]]
        yaw = d.qpos[lay.ee_qpos[3]]
        return Observation(
            t=float(d.time), ee=d.qpos[lay.ee_qpos].copy(), ee_vel=d.qvel[lay.ee_dof].copy(),
            fingers=d.qpos[lay.finger_qpos].copy(), finger_vel=d.qvel[lay.finger_dof].copy(),
            force=tared_force_world(raw_f, yaw, lay.hand_weight_n),
            torque=d.sensordata[lay.sensors["ft_torque"]].copy(),
            touch=np.array([d.sensordata[lay.sensors["touch_l"]][0], d.sensordata[lay.sensors["touch_r"]][0]]),
            objects=self._objects(), ctrl=d.ctrl.copy(),
        )

    def act(self, action: np.ndarray | Plan, duration_s: float, feedback: Feedback | None = None,
            on_tick: Callable[[Observation], None] | None = None) -> Observation:
        """Send `action` (x, y, z, yaw, opening targets; or a plan over sim time) for `duration_s`,
        corrected by `feedback` at the inner rate; every inner tick is logged and its new observation passed to
        `on_tick` (a condition that must hold without a break is watched at this rate). Returns the last one."""
        w = self._world
        ticks = max(1, round(duration_s / self.inner_dt))
        obs = self.observe()
        for _ in range(ticks):
            planned = action(obs.t) if callable(action) else action
            u = feedback(obs, planned) if feedback is not None else planned
            u = np.clip(u, self.ctrlrange[:, 0], self.ctrlrange[:, 1])
            w.data.ctrl[:] = u
            self.log.add(obs, u)
            w.step(self._steps_per_tick)
            for watch in self._watchers:
                watch(w)
            obs = self.observe()
            if on_tick is not None:
                on_tick(obs)
        return obs

    def restart(self) -> Observation:
        """Put the scene back as it was at the start (an experimenter's reset between attempts).

        Sim time keeps running, so a trial's attempts follow one another on one clock.
        """
        w = self._world
        t = float(w.data.time)
        mujoco.mj_setState(w.model, w.data, self._initial, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        w.data.time = t
        mujoco.mj_forward(w.model, w.data)
        self.attempts += 1
        if self._estimator is not None:
            self._estimator.reset()
        for hook in self._on_restart:
            hook()
        return self.observe()

    def camera_image(self) -> np.ndarray:
        """(H, W, 3) uint8 RGB of the fixed scene camera (`camera.*`: pose, field of view, size), rendered
        offscreen (MUJOCO_GL=egl): what a camera beside the table sees (no planner overlays)."""
        r = self._world.renderer()
        r.update_scene(self._world.data, camera="scene")
        return r.render().copy()

    def new_log(self) -> ExecutionLog:
        """Start a fresh log (a new attempt); returns the finished one."""
        done, self.log = self.log, ExecutionLog()
        return done
