"""The robot as a method sees it: atomic actions in, observations out.

Methods and reasoners get a `TabletopRobot`, never the world: ground truth (where
objects really are) is not reachable from here. Object features come from
`ObjectPerception` (perceived from renders, or ground truth only when the config's
`perception.objects` says "truth" - the switch lives in perceive.py and is recorded
in every observation's `features_source`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Literal, Protocol

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from kintsugi.core.config import StrictModel
from kintsugi.perception.features import ObjectFeatures
from kintsugi.worlds.tabletop.actions import Drive, parse_action
from kintsugi.worlds.tabletop.arm_model import base_position
from kintsugi.worlds.tabletop.config import ARMS
from kintsugi.worlds.tabletop.ik import ArmIK
from kintsugi.worlds.tabletop.motion import planned_duration, run_programs
from kintsugi.worlds.tabletop.perceive import ObjectPerception
from kintsugi.worlds.tabletop.planning import ArmView, InHand, Planner, PlanError
from kintsugi.worlds.tabletop.scene import CAMERAS
from kintsugi.worlds.tabletop.world import TabletopWorld

Vec3 = tuple[float, float, float]
NEEDS_FEATURES = ("grasp", "move_to_obj", "place", "push")
LETS_GO = ("open_gripper", "close_gripper", "place", "push")
"""Actions after which the hand no longer holds what a grasp took, as it took it."""


HELD_MIN_OPENING_M = 0.01
"""A hand commanded closed that still stands at least this open has something between its fingers."""


def held_objects(touching: dict[str, int], opening: float, closed: bool) -> frozenset[str]:
    """What the hand holds, from its tactile pads and its gripper: every object both pads touch; or the one
    object one pad touches when the hand, commanded closed, is held open by it and the other pad touches
    nothing. A lying bottle pinched off its equator, or a cup hanging on one finger, can lose one pad's contact
    for a few control steps while it stays in the hand (the opening stays at its width); an object that left
    the hand lets the fingers close or touches no pad."""
    both = frozenset(k for k, n in touching.items() if n == 2)
    if both or not closed or opening < HELD_MIN_OPENING_M or len(touching) != 1:
        return both
    return frozenset(k for k, n in touching.items() if n == 1)


class ArmState(StrictModel):
    """One arm as its own sensors report it (joint encoders, gripper, finger-pad touch)."""

    joints_deg: tuple[float, ...]
    tcp_pos: Vec3
    tcp_rpy_deg: Vec3
    """Extrinsic x-y-z angles of the gripper frame (z = approach, y = closing axis)."""
    gripper_opening_m: float
    gripper_closed: bool
    """The commanded state (the paper's binary open/closed feature)."""
    touching: dict[str, int]
    """Objects touching the finger pads -> how many of the two pads touch each."""
    pad_force_n: float

    @property
    def held(self) -> frozenset[str]:
        """What the hand holds (`held_objects`)."""
        return held_objects(self.touching, self.gripper_opening_m, self.gripper_closed)


class Observation(StrictModel):
    """Everything a method may know at one instant: images, perceived objects, the arms."""

    t: float
    features_source: Literal["perceived", "truth"]
    objects: dict[str, ObjectFeatures]
    arms: dict[str, ArmState]
    images_png: dict[str, bytes]
    """RGB of each camera (top, front) as PNG; empty when not requested."""


class ActionResult(StrictModel):
    action: str
    arms: tuple[str, ...]
    reached: bool
    """Every move of the action ended at its target (within motion.reach_tol_*), settled."""
    planned: bool = True
    """False when the action could not be planned (unreachable, or its object not seen): nothing moved."""
    ik_failed: bool = False
    clipped: bool = False
    unseen: bool = False
    """Not planned because the object it acts on is not visible to the cameras (hidden, or out of view)."""
    interrupted: bool = False
    """A step observer stopped the action before it finished (the arms hold where they were commanded)."""
    steps: int = 0
    sim_time: float = 0.0
    pos_err_m: float = 0.0
    rot_err_deg: float = 0.0
    message: str = ""


class ActionHook(Protocol):
    def begin_action(self, planned_s: float, arms: tuple[str, ...]) -> None: ...


@dataclass(frozen=True, slots=True)
class ControlStep:
    """One control period of a running atomic action, as a step observer is told of it."""

    index: int
    """Control steps this robot has run since it was built (the tick just finished is `index`)."""
    t: float
    action: str
    arms: tuple[str, ...]
    step_in_action: int
    """1 on the action's first control step."""


@dataclass(frozen=True, slots=True)
class GripSense:
    """The cheap per-control-step read of one arm: tool position, gripper, which objects both finger pads
    touch (what encoders and tactile pads give at control rate, without images or joint bookkeeping)."""

    eef: tuple[float, float, float]
    opening: float
    closed: bool
    touching: frozenset[str]
    """What the hand holds (`held_objects`: both finger pads, or one pad with the hand held open by it)."""
    pad_force_n: float


StepObserver = Callable[[ControlStep], "bool | None"]
"""Called after every control step of an atomic action; reads the robot (sensors, features) as it likes.
Returning True asks the robot to stop the running action at once (a monitor fired)."""


def _rpy_deg(rot: np.ndarray) -> Vec3:
    """Extrinsic x-y-z angles; at gimbal lock (gripper horizontal, pitch 90 deg) scipy sets the third
    to zero, which still describes the same rotation, so its warning is noise here."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return tuple(float(v) for v in Rotation.from_matrix(rot).as_euler("xyz", degrees=True))


def png(image: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    if not ok:
        raise ValueError("could not encode a camera image as PNG")
    return buf.tobytes()


class TabletopRobot:
    def __init__(self, world: TabletopWorld, hook: ActionHook | None = None,
                 on_tick: Callable[[], None] | None = None) -> None:
        self._world = world
        self._hook = hook
        self._on_tick = on_tick
        cfg = world.cfg
        self._motion = cfg.motion
        self._iks = {arm: ArmIK(cfg.robot, cfg.motion, arm) for arm in ARMS}
        self._planner = Planner(cfg, self._iks, world.shapes)
        self._perception = ObjectPerception(world)
        self.objects: tuple[str, ...] = world.objects
        self.features_source = self._perception.mode
        self.bases = {arm: np.array(base_position(cfg.robot, arm)) for arm in ARMS}
        self.cameras = CAMERAS
        self._in_hand: dict[str, InHand] = {}
        """Per arm, how the hand took what it holds (set by a grasp that ran, forgotten when the hand opens or
        closes again): a place reads it when the held object is hidden in the hand."""
        self.step_observers: list[StepObserver] = []
        """Per-control-step observers (online monitors, trajectory loggers): each is called after every
        control step of every atomic action, in list order, all of them every step; any returning True
        interrupts the running action (the result says `interrupted`)."""
        self.control_steps = 0
        """Control steps run by atomic actions so far (what `ControlStep.index` counts)."""

    @property
    def sim_time(self) -> float:
        return float(self._world.data.time)

    # --- sensing ------------------------------------------------------------------
    def features(self, names: Iterable[str] | None = None) -> dict[str, ObjectFeatures]:
        """Object features as the configured source gives them (perceived by default)."""
        return self._perception.features(names)

    def arm_state(self, arm: str) -> ArmState:
        w = self._world
        pos, rot = w.tcp_pose(arm)
        touching, force = w.pad_contacts(arm)
        return ArmState(
            joints_deg=tuple(round(float(v), 3) for v in np.degrees(w.joint_positions(arm))),
            tcp_pos=tuple(float(v) for v in pos),
            tcp_rpy_deg=_rpy_deg(rot),
            gripper_opening_m=w.gripper_opening(arm), gripper_closed=w.gripper_commanded_closed(arm),
            touching=touching, pad_force_n=force)

    def joint_command_deg(self, arm: str) -> tuple[float, ...]:
        """The joint position targets this robot's controller is commanding now (its own output, not a
        measurement): what a trajectory logger records as the action of a control step."""
        return tuple(float(v) for v in np.degrees(self._world.joint_targets(arm)))

    def grip_sense(self, arm: str) -> GripSense:
        """Proprioception and finger-pad touch only: cheap enough to read every control step."""
        w = self._world
        pos, _ = w.tcp_pose(arm)
        touching, force = w.pad_contacts(arm)
        opening, closed = w.gripper_opening(arm), w.gripper_commanded_closed(arm)
        return GripSense(eef=(float(pos[0]), float(pos[1]), float(pos[2])), opening=opening, closed=closed,
                         touching=held_objects(touching, opening, closed), pad_force_n=force)

    def observation(self, images: bool = True) -> Observation:
        return Observation(
            t=self.sim_time, features_source=self.features_source, objects=self.features(),
            arms={arm: self.arm_state(arm) for arm in ARMS},
            images_png={c: png(self._world.render(c)) for c in CAMERAS} if images else {})

    def image(self, camera: str) -> np.ndarray:
        return self._world.render(camera)

    # --- acting -------------------------------------------------------------------
    def execute(self, action: dict[str, Any] | Any, plan_only: bool = False) -> ActionResult:
        """Validate, plan (all IK up front), then move. Bad input raises ActionError before any motion;
        an unreachable target returns ik_failed=True without moving. `plan_only`: stop after planning (whether
        the arm can do it, and whether a target had to be clipped to the workspace), nothing moves."""
        if isinstance(action, dict):
            action = parse_action(action, self.objects)
        parts = [a for a in (action.left, action.right) if a is not None] if isinstance(action, Drive) else [action]
        arms = tuple(p.arm for p in parts)
        steps0, t0 = self._world.steps, self.sim_time
        feats = None
        if any(p.action in NEEDS_FEATURES for p in parts):  # perceive only what the action refers to
            needed = {o for p in parts for o in p.objects}
            if any(p.action in ("grasp", "push") for p in parts):  # its way in must clear every object
                needed |= set(self.objects)
            needed |= {k for p in parts if p.action == "place" for k in self._world.pad_contacts(p.arm)[0]}
            feats = self._perception.features(needed)
        self._planner.clipped = False
        try:
            programs = {p.arm: self._planner.plan(p, self._arm_view(p.arm), feats) for p in parts}
        except PlanError as exc:
            return ActionResult(action=action.action, arms=arms, reached=False, planned=False, ik_failed=exc.ik_failed,
                                clipped=exc.clipped, unseen=exc.unseen, message=str(exc))
        if plan_only:
            return ActionResult(action=action.action, arms=arms, reached=False, clipped=self._planner.clipped,
                                message="planned" + (", target clipped to the workspace" if self._planner.clipped
                                                     else ""))
        if self._hook is not None:
            planned = max(planned_duration(s, self._world.joint_targets(a), self._motion) for a, s in programs.items())
            self._hook.begin_action(planned, arms)
        stopped = [False]
        first = self.control_steps

        def observe() -> bool:
            self.control_steps += 1
            if self.step_observers:
                step = ControlStep(self.control_steps, self.sim_time, action.action, arms, self.control_steps - first)
                for obs in list(self.step_observers):
                    if obs(step):
                        stopped[0] = True
            return stopped[0]

        for p in parts:  # what each hand now holds, as it took it
            took = self._planner.grasped.get(p.arm) if p.action == "grasp" else None
            if took is not None or p.action in LETS_GO:
                self._in_hand.pop(p.arm, None)
            if took is not None:
                self._in_hand[p.arm] = took
        reports = run_programs(self._world, programs, self._motion, self._on_tick, observe)
        if stopped[0]:
            return ActionResult(action=action.action, arms=arms, reached=False, clipped=self._planner.clipped,
                                interrupted=True, steps=self._world.steps - steps0, sim_time=self.sim_time - t0,
                                message=f"interrupted by a step observer after {self.control_steps - first} "
                                        "control steps")
        pos_err = max((r.pos_err_m for rs in reports.values() for r in rs), default=0.0)
        rot_err = max((r.rot_err_deg for rs in reports.values() for r in rs), default=0.0)
        settled = all(r.settled for rs in reports.values() for r in rs)
        reached = settled and pos_err <= self._motion.reach_tol_m and rot_err <= self._motion.reach_tol_deg
        msg = (f"pose error {pos_err * 1000:.1f} mm, {rot_err:.1f} deg" + ("" if settled else ", not settled")
               + (", target clipped to the workspace" if self._planner.clipped else ""))
        return ActionResult(action=action.action, arms=arms, reached=reached, clipped=self._planner.clipped,
                            steps=self._world.steps - steps0, sim_time=self.sim_time - t0, pos_err_m=pos_err,
                            rot_err_deg=rot_err, message=msg)

    def _arm_view(self, arm: str) -> ArmView:
        q = self._world.joint_targets(arm)
        pos, rot = self._iks[arm].fk(q)
        return ArmView(q=q, pos=pos, rot=rot, base=self.bases[arm], touching=self._world.pad_contacts(arm)[0],
                       in_hand=self._in_hand.get(arm))
