"""The robot as a method sees it: skills, its own pose, the wrist sensor, the camera, its description.

Methods and reasoners get a `PegRobot`, never the `PegWorld`: ground truth
(where the hole really is, how deep the peg is, the trial's parameters) is not
reachable from here. What the robot knows about itself comes from the config
it was built with and the peg the task names (`description`), never from the
world's randomized truth.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from kintsugi.perception.types import CameraCalibration, Pose
from kintsugi.worlds.peg.description import RobotDescription
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import full_goals
from kintsugi.worlds.peg.shapes import MM, peg_shape
from kintsugi.worlds.peg.skills import AXES, SKILLS, SkillResult, execute_skill
from kintsugi.worlds.peg.world import HOME_POSE, PegWorld


class PegRobot:
    def __init__(self, world: PegWorld, shape: str, on_tick: Callable[[PegWorld], None] | None = None) -> None:
        """`shape` is the peg the task hands the robot (the trial's variant), as the task text names it."""
        self._world = world
        self._on_tick = on_tick
        self._cfg = world.cfg
        self.calibration: CameraCalibration = world.calibration()
        self.side_calibration: CameraCalibration | None = world.side_calibration() if world.has_side_view else None
        """The optional side camera (x-z plane); None when the robot has none (the paper's setup)."""
        self.shape = shape
        self.skill_axes = {name: list(spec.axes) for name, spec in SKILLS.items()}
        self.current_skill = ""
        self.status = ""

    def description(self, goals: dict[str, dict[str, float]]) -> RobotDescription:
        """This robot's description for reasoners; `goals` are the taught goals its skills command."""
        return describe_robot(self._cfg, self.shape, goals)

    def pose(self) -> np.ndarray:
        return self._world.base_pose()

    def image(self) -> np.ndarray:
        return self._world.render()

    def side_image(self) -> np.ndarray | None:
        """The side camera's view, or None without one."""
        return self._world.render_side() if self.side_calibration is not None else None

    def wrist_force_z(self) -> float:
        """Tared wrist force along z (N), as the arm's F/T sensor reports it."""
        return self._world.wrist_compression() * self._cfg.wrist.z_stiffness

    def execute(self, skill: str, goal: np.ndarray) -> SkillResult:
        self.current_skill = skill
        return execute_skill(self._world, skill, goal, on_tick=self._on_tick)

    @property
    def sim_time(self) -> float:
        return float(self._world.data.time)


def describe_robot(cfg: PegTaskConfig, shape: str, goals: dict[str, dict[str, float]]) -> RobotDescription:
    """The robot's own knowledge: build config, the named peg's nominal size, the taught contact press.

    The contact press is the robot's own command: at the taught approach roll the peg's lowest
    corner is `L cos r + (w / 2) sin |r|` below the compliance centre, so the taught contact z
    presses it that far below the board surface (which the task places at
    `perception.board_surface_z_mm`). Nothing here reads a world or a trial's parameters.
    """
    peg = peg_shape(shape, cfg)
    depth_mm, tilt_deg = insert_requirements(cfg)
    width_mm = 2 * peg.half_y / MM
    lever_mm = cfg.wrist.hinge_to_grasp_mm + cfg.peg.length_mm
    contact = full_goals(goals, HOME_POSE)["contact"]
    roll = float(contact[AXES.index("roll")])
    lowest_mm = lever_mm * math.cos(roll) + width_mm / 2 * abs(math.sin(roll))
    base_above_surface_mm = float(contact[AXES.index("z")]) / MM - cfg.perception.board_surface_z_mm
    return RobotDescription(
        peg_shape=shape, peg_width_mm=round(width_mm, 3), peg_length_mm=cfg.peg.length_mm,
        hole_clearance_mm=cfg.peg.clearance_mm, hole_depth_mm=cfg.hole.depth_mm,
        compliance_to_tip_mm=lever_mm, wrist_z_stiffness_n_per_mm=cfg.wrist.z_stiffness / 1000.0,
        wrist_roll_stiffness_nm_per_rad=cfg.wrist.roll_stiffness,
        contact_press_mm=round(lowest_mm - base_above_surface_mm, 3),
        compression_limit_mm=cfg.control.compression_limit_mm, pose_tol_mm=cfg.control.pose_tol_mm,
        insert_depth_mm=round(depth_mm, 3), insert_max_tilt_deg=round(tilt_deg, 3), vision=cfg.perception,
    )


def insert_requirements(cfg: PegTaskConfig) -> tuple[float, float]:
    """(depth mm, tilt deg) the task asks of an inserted peg, from the config's scoring values: the tip
    `scoring.min_depth_fraction` of the hole depth down, and the axis within `scoring.max_tilt_deg`, by
    default atan(clearance / that depth), the largest tilt a rigid peg seated that deep can have across
    the hole's flats."""
    depth = cfg.scoring.min_depth_fraction * cfg.hole.depth_mm
    tilt = cfg.scoring.max_tilt_deg
    if tilt is None:
        tilt = math.degrees(math.atan2(cfg.peg.clearance_mm, depth))
    return depth, tilt


def to_pose(v: np.ndarray) -> Pose:
    """SI [y, z, roll] -> reasoner units (mm, mm, deg)."""
    return Pose(y=round(float(v[0]) * 1000, 3), z=round(float(v[1]) * 1000, 3), roll=round(float(np.degrees(v[2])), 3))
