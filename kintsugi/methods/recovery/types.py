"""Typed requests and replies for each reasoner role (judge, analyze, plan).

These are everything a reasoner may see: images (PNG bytes, as a model would
receive them), robot poses, sensor flags, check results, camera calibration
and the task text. Nothing here comes from simulator ground truth.
Units follow what a person (or a model) reads best: millimetres and degrees.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from kintsugi.core.config import StrictModel

Role = Literal["judge", "analyze", "plan"]
"""The peg recovery's roles; other systems add theirs through `kintsugi.reasoning.roles` (any role name)."""
RecoverySkill = Literal["approach", "contact", "fit", "align", "insert"]
"""Every skill a plan may name; a request's `skills` says which of them this robot's recovery allows."""
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


HSV = tuple[int, int, int]
KernelPx = Annotated[int, Field(ge=1, le=31)]


class HsvRange(StrictModel):
    """Inclusive OpenCV HSV bounds (H in 0..180, S and V in 0..255)."""

    lower: HSV
    upper: HSV


class PerceptionConfig(StrictModel):
    """Colour thresholds, mask clean-up and the tolerances the checks use (`--set perception.*`).

    Defined here rather than in `kintsugi.perception` because reasoners are told it: the
    embedded reasoner measures images with the same settings as the checks.
    """

    peg_hsv: list[HsvRange] = Field(
        default_factory=lambda: [HsvRange(lower=(78, 90, 40), upper=(102, 255, 255))],
        description="cyan peg; hue 90 is pure cyan",
    )
    hole_hsv: list[HsvRange] = Field(
        default_factory=lambda: [
            HsvRange(lower=(0, 110, 40), upper=(10, 255, 255)),
            HsvRange(lower=(170, 110, 40), upper=(180, 255, 255)),
        ],
        description="red wraps around hue 0/180, hence two ranges",
    )
    open_kernel_px: KernelPx = 3
    close_kernel_px: KernelPx = 5
    min_area_px: float = Field(default=40.0, ge=0)
    align_tol_mm: float = Field(default=3.0, ge=0, description="|P_center - H_center| counted as 'on the hole'")
    tilt_tol_deg: float = Field(default=5.0, ge=0, description="tilt within ±this is 'vertical'")
    insert_top_tol_mm: float = Field(default=3.0, ge=0, description="peg-top height match vs the goal image")
    insert_min_iou: float = Field(default=0.5, ge=0, le=1, description="peg masks must overlap at least this")
    board_surface_z_mm: float = Field(default=0.0, description="used when the board line is not found in the image")


class RobotDescription(StrictModel):
    """What the robot knows about itself and what the task states, from the config it was built with.

    A real robot knows its own build (wrist springs, gripper, the peg it was handed, the commands
    its skills send) and its vision settings; it does not know a trial's randomized truth (where
    the hole really is, the in-grasp angle, the friction), nor the ranges that truth is drawn
    from, and neither appears here. Reasoners derive their thresholds from this description.
    """

    peg_shape: str
    peg_width_mm: float = Field(description="nominal width of the peg in the camera's image plane (along y)")
    peg_length_mm: float
    hole_clearance_mm: float = Field(description="hole width minus peg width, as the task states it")
    hole_depth_mm: float
    compliance_to_tip_mm: float = Field(
        description="from the wrist's compliance centre (roll hinge, at the base pose) to the peg tip along the peg; "
                    "a base shift d tilts a peg pivoting on its tip by about atan(d / this)")
    wrist_z_stiffness_n_per_mm: float
    wrist_roll_stiffness_nm_per_rad: float
    contact_press_mm: float = Field(
        description="wrist compression the taught contact goal commands on the board surface (the press fit starts "
                    "with); a tip that drops into the hole relieves part of it")
    compression_limit_mm: float = Field(description="a skill halts at once when the wrist is compressed beyond this")
    pose_tol_mm: float = Field(description="a goal counts as reached within this distance")
    insert_depth_mm: float = Field(
        description="the task's depth: inserted means the peg tip at least this far below the board top, "
                    "inside the opening")
    insert_max_tilt_deg: float = Field(
        description="the task's tilt bound: inserted means the peg axis within this of vertical (a peg tilted "
                    "further is wedged against the walls, not inserted)")
    vision: PerceptionConfig = Field(description="the settings the vision checks measure the images with")

    @property
    def hole_width_mm(self) -> float:
        return self.peg_width_mm + self.hole_clearance_mm

    @property
    def contact_press_n(self) -> float:
        return self.contact_press_mm * self.wrist_z_stiffness_n_per_mm

    @property
    def compression_limit_n(self) -> float:
        return self.compression_limit_mm * self.wrist_z_stiffness_n_per_mm


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


class CallRecord(StrictModel):
    """One reasoner call as kept in the trial transcript."""

    role: str = Field(min_length=1, max_length=40, description="judge, analyze, plan, or another system's role")
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
