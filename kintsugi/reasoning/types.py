"""Typed requests and replies for each reasoner role (judge, analyze, plan).

These are everything a reasoner may see: images (PNG bytes, as a model would
receive them), robot poses, sensor flags, check results, camera calibration
and the task text. Nothing here comes from simulator ground truth.
Units follow what a person (or a model) reads best: millimetres and degrees.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from kintsugi.config import StrictModel

Role = Literal["judge", "analyze", "plan"]
RecoverySkill = Literal["fit", "align", "insert"]
Axis = Literal["y", "z", "roll"]


class Pose(StrictModel):
    """Wrist-base pose in the task plane: y and z in mm, roll in degrees."""

    y: float
    z: float
    roll: float = 0.0


class CameraCalibration(StrictModel):
    """Pinhole camera viewing the y-z task plane: pixel <-> millimetre on that plane.

    u = cu + fy_px_per_mm * (y - y0), v = cv - fz_px_per_mm * (z - z0).
    """

    width: int
    height: int
    px_per_mm: float
    cu: float
    cv: float
    y0_mm: float
    z0_mm: float

    def to_pixel(self, y_mm: float, z_mm: float) -> tuple[float, float]:
        return self.cu + self.px_per_mm * (y_mm - self.y0_mm), self.cv - self.px_per_mm * (z_mm - self.z0_mm)

    def to_plane(self, u: float, v: float) -> tuple[float, float]:
        return self.y0_mm + (u - self.cu) / self.px_per_mm, self.z0_mm - (v - self.cv) / self.px_per_mm


class CheckResult(StrictModel):
    """One mechanical check (vision, pose, compression limit) and its message."""

    name: str
    passed: bool
    message: str
    measurements: dict[str, float] = Field(default_factory=dict)


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


class JudgeRequest(StrictModel):
    task: str
    outcome: SkillOutcome
    checks: list[CheckResult]
    success_criteria: str
    goal_image_png: bytes | None = Field(default=None, repr=False)
    calibration: CameraCalibration


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
    max_step_mm: float
    skills: dict[str, list[Axis]] = Field(
        default_factory=dict, description="recovery skill -> the axes it controls (fit [y], align [y], insert [z])"
    )
    goal_image_png: bytes | None = Field(
        default=None, repr=False, description="I_g: the failed skill's terminal image in the default condition"
    )


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


class PlanStep(StrictModel):
    skill: RecoverySkill
    goal: dict[Axis, float] = Field(default_factory=dict, description="absolute goal values for the skill's own axes")


class PlanReply(StrictModel):
    steps: list[PlanStep] = Field(min_length=1, max_length=6)


class CallRecord(StrictModel):
    """One reasoner call as kept in the trial transcript."""

    role: Role
    backend: str
    request: dict
    reply: dict | None
    error: str | None = None
    latency_s: float = 0.0
    tokens_in: int = 0
    tokens_out: int = 0
    attempts: int = 1
    output_mode: Literal["strict", "text"] | None = None
    """How an endpoint enforced the reply format (None for backends without one, e.g. embedded)."""
    output_note: str | None = None
    """Set on the call where the backend fell back from strict to text output, with the reason."""
