"""Every world parameter and randomization range of the peg-insertion task, typed.

Lengths are in millimetres, angles in degrees, as a user types them on the
command line (`--set hole.friction_scale=[1,5]`); the scene builder converts.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from kintsugi.core.config import Range, SimSection as BaseSim, StrictModel
from kintsugi.perception.segment import PerceptionConfig


RECOVERY_SKILL_NAMES = ("approach", "contact", "fit", "align", "insert")
"""The contact-formation skills CF0..CF4, by name, in order (kept in step with skills.SKILLS)."""


class PegSection(StrictModel):
    diameter_mm: float = Field(40.0, gt=0)
    square_mm: float = Field(40.0, gt=0)
    rectangle_mm: tuple[float, float] = (40.0, 20.0)
    """Rectangle sides: first along y (in the image plane), second along x (depth)."""
    polygon_circumradius_mm: float = Field(23.0, gt=0)
    length_mm: float = Field(100.0, gt=40)
    mass_kg: float = Field(0.05, gt=0)
    friction: float = Field(0.3, ge=0)
    clearance_mm: float = Field(2.0, gt=0, lt=20)
    """Diametral clearance between peg and hole (hole = peg + clearance)."""


class HoleSection(StrictModel):
    depth_mm: float = Field(40.0, ge=30)
    round_sides: int = Field(32, ge=8, le=96)
    """The round hole is a regular polygon of this many walls (MuJoCo colliders are convex)."""
    friction: float = Field(0.3, ge=0)
    friction_scale: Range = (1.0, 5.0)
    """Applied by the `friction` and `all` conditions."""
    y_offset_mm: Range = (-20.0, 20.0)
    """Hole position error along y; applied by the `pose` and `all` conditions."""
    x_offset_mm: Range = (0.0, 0.0)
    """Hole position error along x, out of the main camera's plane (off by default, as in the
    paper); applied by the `pose` and `all` conditions."""


class GraspSection(StrictModel):
    angle_deg: Range = (-5.0, 5.0)
    """In-grasp roll angle of the peg; applied by the `pose` and `all` conditions."""
    depth_mm: float = Field(20.0, gt=0)
    """How much of the peg is inside the fingers."""


class WristSection(StrictModel):
    """Soft wrist: published values of Fuchioka et al. 2024 (z slide, roll, pitch, yaw)."""

    z_stiffness: float = Field(1000.0, gt=0)
    z_damping: float = Field(1.0, ge=0)
    roll_stiffness: float = Field(0.5, gt=0)
    roll_damping: float = Field(0.005, ge=0)
    pitch_stiffness: float = Field(0.5, gt=0)
    pitch_damping: float = Field(0.005, ge=0)
    yaw_stiffness: float = Field(5.0, gt=0)
    yaw_damping: float = Field(1.0, ge=0)
    gripper_mass_kg: float = Field(0.2, gt=0)
    hinge_to_grasp_mm: float = Field(40.0, gt=0)
    """Distance from the wrist's compliance centre down to the top of the fingers' grasp."""
    gravity_preload: bool = True
    """Preload the z spring so the hanging wrist rests at zero compression."""


class ControlSection(StrictModel):
    rate_hz: float = Field(250.0, gt=0)
    speed_mm_s: float = Field(40.0, gt=0)
    rot_speed_deg_s: float = Field(40.0, gt=0)
    pose_tol_mm: float = Field(1.0, gt=0)
    settle_s: float = Field(0.2, ge=0)
    """Minimum wait at the goal; then wait (up to settle_max_s) until the wrist stops swinging."""
    settle_max_s: float = Field(1.5, ge=0)
    timeout_s: float = Field(6.0, gt=0)
    compression_limit_mm: float = Field(20.0, gt=0)
    """The running skill halts at once when the z spring is compressed beyond this."""
    goals_file: str | None = None
    """Taught goals (JSON, mm / deg) written by `bench/teach_goals.py --out`; None = the shipped default_goals.json."""


class CameraSection(StrictModel):
    width: int = Field(320, ge=64, le=2048)
    height: int = Field(240, ge=48, le=2048)
    view_height_mm: float = Field(150.0, gt=10)
    center_y_mm: float = -10.0
    center_z_mm: float = 30.0
    side_view: bool = False
    """Add a second orthographic camera viewing the x-z plane (from -y), same size and scale,
    with the hole's section painted on the board's side face; off as in the paper."""
    center_x_mm: float = 0.0
    """Horizontal image centre of the side view (its image right is +x)."""


class SimSection(BaseSim):
    timestep_s: float = Field(0.001, gt=0, le=0.005)
    contact_timeconst_s: float = Field(0.002, gt=0)
    """Contact stiffness (MuJoCo solref); must be >= 2 x timestep."""
    noslip_iterations: int = Field(0, ge=0)


class ScoringSection(StrictModel):
    """Ground truth G (scoring only; no method reads the world's truth)."""

    min_depth_fraction: float = Field(0.5, gt=0, le=1)
    """The peg tip must be at least this fraction of the hole depth below the board top,
    inside the opening's footprint."""
    max_tilt_deg: float | None = Field(None, gt=0, lt=90)
    """Largest tilt of the peg axis from vertical. None: the largest tilt a rigid peg seated at
    the minimum depth can have, atan(gap / depth), the gap being the hole's width minus the
    peg's in the direction it leans (5.7 deg across flats with the default 2 mm clearance)."""


class PegTaskConfig(StrictModel):
    peg: PegSection = PegSection()
    hole: HoleSection = HoleSection()
    grasp: GraspSection = GraspSection()
    wrist: WristSection = WristSection()
    control: ControlSection = ControlSection()
    camera: CameraSection = CameraSection()
    sim: SimSection = SimSection()
    perception: PerceptionConfig = PerceptionConfig()
    scoring: ScoringSection = ScoringSection()


Condition = Literal["none", "friction", "pose", "all"]
CONDITIONS: dict[str, str] = {
    "none": "nominal world: aligned grasp, hole at its taught place, nominal friction",
    "friction": "hole surface friction scaled by hole.friction_scale",
    "pose": "hole offset by hole.y_offset_mm and in-grasp angle by grasp.angle_deg",
    "all": "friction and pose randomization together",
}
