"""Typed requests and replies of the peg recovery's roles (judge, analyze, plan).

These are everything a reasoner may see: images (PNG bytes, as a model would
receive them), robot poses, sensor flags, check results, camera calibration
and the task text. Nothing here comes from simulator ground truth.
Units follow what a person (or a model) reads best: millimetres and degrees.
The observation types (poses, calibrations, check results) are perception's
(`kintsugi.perception.types`); the robot's description is the peg robot's own
(`kintsugi.worlds.peg.description`).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.perception.types import Axis, CameraCalibration, CheckResult, Pose
from kintsugi.worlds.peg.description import RobotDescription

RecoverySkill = Literal["approach", "contact", "fit", "align", "insert"]
"""Every skill a plan may name; a request's `skills` says which of them this robot's recovery allows."""


class SkillOutcome(StrictModel):
    """What the robot knows at the end of one skill execution."""

    skill: str
    goal: Pose
    terminal: Pose
    reached_goal: bool
    timed_out: bool
    compression_limit: bool
    wrist_force_z_n: float = 0.0
    image_png: bytes = Field(repr=False)
    side_image_png: bytes | None = Field(
        default=None, repr=False,
        description="the side camera's image (the x-z plane, image right = +x), when the robot has one")


class JudgeRequest(StrictModel):
    task: str
    outcome: SkillOutcome
    checks: list[CheckResult]
    success_criteria: str
    goal_image_png: bytes | None = Field(default=None, repr=False)
    calibration: CameraCalibration
    side_calibration: CameraCalibration | None = Field(
        default=None, description="the side camera's calibration (its horizontal axis is x: to_plane gives x, z)")
    robot: RobotDescription | None = Field(
        default=None, description="the robot's own description; None when the caller does not describe it")


class JudgeReply(StrictModel):
    success: bool
    explanation: str = Field(max_length=2000)


class Attempt(StrictModel):
    """A past execution in this trial, summarized for the reasoner's history."""

    skill: str
    goal: Pose
    terminal: Pose
    success: bool
    explanation: str


class AnalyzeRequest(StrictModel):
    task: str
    outcome: SkillOutcome
    checks: list[CheckResult]
    verdict: JudgeReply
    goals: dict[str, Pose]
    history: list[Attempt]
    calibration: CameraCalibration
    side_calibration: CameraCalibration | None = Field(
        default=None, description="the side camera's calibration (its horizontal axis is x: to_plane gives x, z)")
    max_step_mm: float
    skills: dict[str, list[Axis]] = Field(
        default_factory=dict, description="skills a recovery plan may use -> the axes each controls"
    )
    goal_image_png: bytes | None = Field(
        default=None, repr=False, description="I_g: the failed skill's terminal image in the default condition"
    )
    robot: RobotDescription | None = Field(
        default=None, description="the robot's own description; None when the caller does not describe it")


class RelativeMotion(StrictModel):
    skill: RecoverySkill
    axis: Axis
    delta: float = Field(description="change relative to the current goal, mm (y, z) or degrees (roll)")


class AnalyzeReply(StrictModel):
    what_happened: str = Field(max_length=2000)
    why: str = Field(max_length=2000)
    how_to_recover: str = Field(max_length=2000)
    restart_from: RecoverySkill
    motions: list[RelativeMotion] = Field(default_factory=list, max_length=6)


class PlanRequest(StrictModel):
    task: str
    analysis: AnalyzeReply
    goals: dict[str, Pose]
    skills: dict[str, list[Axis]]
    max_step_mm: float
    workspace: dict[Axis, tuple[float, float]] = Field(
        default_factory=dict, description="absolute bounds per axis, mm (y, z) or degrees (roll)"
    )
    robot: RobotDescription | None = Field(
        default=None, description="the robot's own description; None when the caller does not describe it")


class PlanStep(StrictModel):
    skill: RecoverySkill
    goal: dict[Axis, float] = Field(default_factory=dict, description="absolute goal values for the skill's own axes")


class PlanReply(StrictModel):
    steps: list[PlanStep] = Field(min_length=1, max_length=6)


__all__ = [
    "AnalyzeReply", "AnalyzeRequest", "Attempt", "Axis", "CameraCalibration", "CheckResult", "JudgeReply",
    "JudgeRequest", "PlanReply", "PlanRequest", "PlanStep", "Pose", "RecoverySkill", "RelativeMotion",
    "RobotDescription", "SkillOutcome",
]
