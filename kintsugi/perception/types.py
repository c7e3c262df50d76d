"""What the peg cameras and checks report: poses, camera calibrations, colour thresholds, check results.

These are observations, not a method's vocabulary: the world's robot reports them, the checks
measure with them, and any method (or reasoner) that reads the robot's images and poses uses the
same types. Units follow what a person (or a model) reads best: millimetres and degrees.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from kintsugi.core.config import StrictModel

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

    Reasoners are told it too (in the robot's description): the embedded reasoner measures images
    with the same settings as the checks.
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


class CheckResult(StrictModel):
    """One mechanical check (vision, pose, compression limit) and its message."""

    name: str
    passed: bool
    message: str
    measurements: dict[str, float] = Field(default_factory=dict)
