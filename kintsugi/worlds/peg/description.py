"""What the peg robot knows about itself: its build, its skills' commands and its vision settings."""

from __future__ import annotations

from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.perception.types import PerceptionConfig


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
