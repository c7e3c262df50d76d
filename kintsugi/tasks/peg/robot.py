"""The robot as a method sees it: skills, its own pose, the wrist sensor, the camera.

Methods and reasoners get a `PegRobot`, never the `PegWorld`: ground truth
(where the hole really is, how deep the peg is) is not reachable from here.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from kintsugi.reasoning.types import CameraCalibration, Pose
from kintsugi.tasks.peg.skills import SKILLS, SkillResult, execute_skill
from kintsugi.tasks.peg.world import PegWorld


class PegRobot:
    def __init__(self, world: PegWorld, on_tick: Callable[[PegWorld], None] | None = None) -> None:
        self._world = world
        self._on_tick = on_tick
        self.calibration: CameraCalibration = world.calibration()
        self.shape = world.params.shape
        self.skill_axes = {name: list(spec.axes) for name, spec in SKILLS.items()}
        self.wrist_stiffness_n_per_mm = world.cfg.wrist.z_stiffness / 1000.0
        self.compression_limit_mm = world.cfg.control.compression_limit_mm
        self.current_skill = ""
        self.status = ""

    def pose(self) -> np.ndarray:
        return self._world.base_pose()

    def image(self) -> np.ndarray:
        return self._world.render()

    def wrist_force_z(self) -> float:
        """Tared wrist force along z (N), as the arm's F/T sensor reports it."""
        return self._world.wrist_compression() * self._world.cfg.wrist.z_stiffness

    def execute(self, skill: str, goal: np.ndarray) -> SkillResult:
        self.current_skill = skill
        return execute_skill(self._world, skill, goal, on_tick=self._on_tick)

    @property
    def sim_time(self) -> float:
        return float(self._world.data.time)


def to_pose(v: np.ndarray) -> Pose:
    """SI [y, z, roll] -> reasoner units (mm, mm, deg)."""
    return Pose(y=round(float(v[0]) * 1000, 3), z=round(float(v[1]) * 1000, 3), roll=round(float(np.degrees(v[2])), 3))

