"""Records one tabletop trial as a policy-learning episode, from what the robot and its cameras give.

A `TrajectoryRecorder` is attached to the robot before the method starts (`TabletopTask.run(attach=...)`)
and listens to the trial story (`echo=`). It never touches the world: observations are the robot's own
readings (joint encoders, tool pose by forward kinematics, gripper opening, finger-pad force) and camera
renders; actions are the robot controller's own commands (joint position targets, gripper open/closed).

Frames are taken every `every` control steps (fps = control rate / every). Frame j pairs the observation
at control step j*every with the command in force over the frame's last control step, (j+1)*every, and
the labels of that step; a trailing part of the episode shorter than one frame is not exported.

Labels come from what the method reported: the atomic action a control step belongs to is the one the
trial log was about to record (each `robot.execute` is followed by one `SkillLog`), its nominal/recovery
flag is the log's, and its task-graph edge is the one the method named in its story line for that action
("<t>s [recovery] <edge>: <action> -> ..." as the AgentChord conductor tells it; empty for methods
without a graph).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from rich.errors import MarkupError
from rich.text import Text
from scipy.spatial.transform import Rotation

from kintsugi.core.errors import KintsugiError
from kintsugi.worlds.tabletop.arm_model import JOINTS
from kintsugi.worlds.tabletop.config import ARMS

STORY = re.compile(r"^\s*-?[\d.]+s (?:(?P<rec>recovery) )?(?P<edge>\S+): (?P<action>\w+) -> ")

LOW_DIM: dict[str, int] = {"joint_pos": len(JOINTS), "eef_pos": 3, "eef_quat": 4, "gripper_opening": 1,
                           "pad_force": 1}
"""Per-arm observation keys (robomimic style `<arm>_<key>`) and sizes: joint angles (rad), tool centre point
position (m) and orientation (quaternion x, y, z, w), gripper opening (m), finger-pad normal force (N)."""
ACTION_NAMES: tuple[str, ...] = tuple(n for arm in ARMS for n in (*(f"{arm}_{j}" for j in JOINTS),
                                                                   f"{arm}_gripper_closed"))
"""Action vector: per arm, the joint position targets (rad) then the gripper command (1 closed, 0 open)."""


class RecordingError(KintsugiError):
    """The recording cannot be trusted (a control step it did not see, labels that do not line up)."""


@dataclass
class Episode:
    """One exported trial: T frames of observations, actions and labels, plus the final observation."""

    key: str
    task: str
    instruction: str
    fps: float
    every: int
    control_steps: int
    obs: dict[str, np.ndarray]
    """Frames 0..T (T + 1 rows): rows 0..T-1 are the frames' observations, row T the one after the last."""
    images: dict[str, np.ndarray]
    """Per camera, (T + 1, H, W, 3) uint8, the same rows as `obs`."""
    actions: np.ndarray
    """(T, len(ACTION_NAMES)) float64."""
    recovery: np.ndarray
    """(T,) bool: the frame's command belongs to an action the method marked as recovery."""
    edge: list[str]
    action: list[str]
    action_number: np.ndarray
    """(T,) int: which atomic action of the episode (0-based, in execution order)."""
    success: bool
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def length(self) -> int:
        return len(self.actions)


def _quat_xyzw(rpy_deg: tuple[float, float, float]) -> np.ndarray:
    return Rotation.from_euler("xyz", rpy_deg, degrees=True).as_quat()


class TrajectoryRecorder:
    def __init__(self, every: int) -> None:
        if every < 1:
            raise ValueError("every must be >= 1")
        self.every = every
        self.steps = 0
        self._robot: Any = None
        self._log: Any = None
        self._obs: list[dict[str, np.ndarray]] = []
        self._images: list[dict[str, np.ndarray]] = []
        self._commands: list[np.ndarray] = []
        self._rows: list[tuple[int, str]] = []
        self._edges: dict[int, tuple[str, bool, str]] = {}
        self._missed: str | None = None

    # --- hooks ----------------------------------------------------------------------
    def attach(self, robot: Any, log: Any) -> None:
        """Given the robot and trial log before the method starts: take frame 0, then watch every step."""
        self._robot, self._log = robot, log
        self._snapshot()
        robot.step_observers.append(self._on_step)

    def echo(self, text: str) -> None:
        """A line of the trial story; an action's line names the graph edge it ran for."""
        if self._log is None:
            return
        try:
            plain = Text.from_markup(text).plain
        except MarkupError:
            plain = text
        m = STORY.match(plain)
        n = len(self._log.skills) - 1
        if m is None or n < 0 or n in self._edges:
            return
        if self._log.skills[n].skill == m["action"]:
            self._edges[n] = (m["edge"], m["rec"] is not None, m["action"])

    def _on_step(self, step: Any) -> None:
        self.steps += 1
        if step.index != self.steps and self._missed is None:
            self._missed = (f"control step {step.index} arrived as the recorder's step {self.steps}: "
                            "the robot ran control steps the recorder did not see")
        if self.steps % self.every == 0:
            self._commands.append(self._command())
            self._rows.append((len(self._log.skills), step.action))
            self._snapshot()
        return None

    # --- reading the robot --------------------------------------------------------------
    def _command(self) -> np.ndarray:
        r = self._robot
        out: list[float] = []
        for arm in ARMS:
            out.extend(np.radians(r.joint_command_deg(arm)))
            out.append(1.0 if r.grip_sense(arm).closed else 0.0)
        return np.asarray(out, dtype=np.float64)

    def _snapshot(self) -> None:
        r = self._robot
        obs: dict[str, np.ndarray] = {}
        for arm in ARMS:
            s = r.arm_state(arm)
            obs[f"{arm}_joint_pos"] = np.radians(np.asarray(s.joints_deg, dtype=np.float64))
            obs[f"{arm}_eef_pos"] = np.asarray(s.tcp_pos, dtype=np.float64)
            q = _quat_xyzw(s.tcp_rpy_deg)
            last = self._obs[-1][f"{arm}_eef_quat"] if self._obs else None
            obs[f"{arm}_eef_quat"] = -q if (last is not None and q @ last < 0) or (last is None and q[3] < 0) else q
            obs[f"{arm}_gripper_opening"] = np.array([s.gripper_opening_m])
            obs[f"{arm}_pad_force"] = np.array([s.pad_force_n])
        self._obs.append(obs)
        self._images.append({c: np.ascontiguousarray(r.image(c)) for c in r.cameras})

    # --- result ---------------------------------------------------------------------------
    def episode(self, key: str, task: str, instruction: str, record: Any, control_hz: float) -> Episode:
        """The episode, labelled from the re-run's record (its skills are the log the steps were counted on)."""
        if self._missed is not None:
            raise RecordingError(self._missed)
        if self._robot is None:
            raise RecordingError("the recorder was never attached to the robot")
        skills = record.skills
        recovery, edges, actions, numbers = [], [], [], []
        for n, name in self._rows:
            if n >= len(skills) or skills[n].skill != name:
                logged = skills[n].skill if n < len(skills) else "nothing"
                raise RecordingError(f"a {name} control step lines up with atomic action {n}, which the log "
                                     f"records as {logged}")
            edge, story_rec, _ = self._edges.get(n, ("", False, name))
            if edge and story_rec != skills[n].recovery:
                raise RecordingError(f"action {n} ({name}): the story and the log disagree on recovery")
            recovery.append(skills[n].recovery)
            edges.append(edge)
            actions.append(name)
            numbers.append(n)
        cams = list(self._images[0])
        width = len(ACTION_NAMES)
        return Episode(
            key=key, task=task, instruction=instruction, fps=control_hz / self.every, every=self.every,
            control_steps=self.steps,
            obs={k: np.stack([o[k] for o in self._obs]) for k in self._obs[0]},
            images={c: np.stack([f[c] for f in self._images]) for c in cams},
            actions=np.stack(self._commands) if self._commands else np.zeros((0, width)),
            recovery=np.asarray(recovery, dtype=bool), edge=edges, action=actions,
            action_number=np.asarray(numbers, dtype=np.int64), success=bool(record.success))
