"""Records any system's trial (peg, tabletop, contact) as a policy-learning episode through its step-level
driver: the robot's own observation (sensors and camera images, with hemisphere-continuous quaternions
and the pad or wrist forces) and the command in force, every `every` control periods.

Frame j pairs the observation just before control period j*every with the command sent over it, the
same actions the step-level API (`kintsugi.methods.policy.drivers`) takes, so a dataset's actions can
be sent back through `gymnasium.make("kintsugi/<Task>-v0")`. Labels: the skill or atomic action a frame
belongs to is the one the trial log records next (each execution is followed by one `SkillLog`), with its
nominal/recovery flag; a contact trial's later attempts (after a restart) are recovery.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.export.recorder import Episode, RecordingError
from kintsugi.methods.policy.drivers import driver_for


class FrameRecorder:
    def __init__(self, every: int) -> None:
        if every < 1:
            raise ValueError("every must be >= 1")
        self.every = every
        self.steps = 0
        self.driver: Any = None
        self._log: Any = None
        self._obs: list[dict[str, np.ndarray]] = []
        self._commands: list[np.ndarray] = []
        self._rows: list[tuple[int, int]] = []
        self._restarts = 0
        self._restart_steps: list[int] = []
        self._marks: list[list] = []

    def attach(self, robot: Any, log: Any) -> None:
        self.driver, self._log = driver_for(robot), log
        self.driver.record_ticks(self._on_tick)
        if hasattr(self.driver, "record_restarts"):
            self.driver.record_restarts(self._on_restart)
        if hasattr(self.driver, "record_actions"):
            self.driver.record_actions(lambda planned, arms: self._marks.append([self.steps, planned, list(arms)]))

    def echo(self, text: str) -> None:
        return None

    def _on_restart(self) -> None:
        self._restarts += 1
        self._restart_steps.append(self.steps)

    def _on_tick(self, command: np.ndarray) -> None:
        if self.steps % self.every == 0:
            self._obs.append(self.driver.observe(images=True))
            self._commands.append(np.asarray(command, dtype=np.float64))
            self._rows.append((len(self._log.skills), self._restarts))
        self.steps += 1

    def episode(self, key: str, task: str, instruction: str, record: Any, control_hz: float) -> Episode:
        if self.driver is None:
            raise RecordingError("the recorder was never attached to the robot")
        if not self._obs:
            raise RecordingError(f"{key}: no control period ran; nothing to export")
        self._obs.append(self.driver.observe(images=True))  # the observation after the last frame
        feats = self.driver.features(images=True)
        images = {k: np.stack([o[k] for o in self._obs]) for k, f in feats.items() if f.image}
        low = {k: np.stack([np.asarray(o[k], dtype=np.float64) for o in self._obs]) for k, f in feats.items()
               if not f.image}
        skills = record.skills
        recovery, names, numbers = [], [], []
        for n, attempt in self._rows:
            s = skills[n] if n < len(skills) else None
            recovery.append(bool(s is not None and s.recovery) or attempt > 0)
            names.append(s.skill if s is not None else "")
            numbers.append(n)
        cams = {k.removeprefix("image_") if k.startswith("image_") else "scene": v for k, v in images.items()}
        return Episode(key=key, task=task, instruction=instruction, fps=control_hz / self.every, every=self.every,
                       control_steps=self.steps, obs=low, images=cams, actions=np.stack(self._commands),
                       recovery=np.asarray(recovery, dtype=bool), edge=[""] * len(names), action=names,
                       action_number=np.asarray(numbers, dtype=np.int64), success=bool(record.success),
                       meta={"action_names": list(self.driver.action_names), "family": self.driver.family,
                             "action_marks": self._marks, "restarts": self._restart_steps,
                             "framework_success": bool(record.framework_success),
                             "features": {k: {"shape": list(f.shape), "unit": f.unit,
                                              "names": list(f.names) if f.names else None}
                                          for k, f in feats.items() if not f.image}})
