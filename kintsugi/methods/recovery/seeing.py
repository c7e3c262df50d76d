"""What the embedded peg reasoner measures on the images it is sent, and the rules' shared proportions.

It decodes the same PNGs a model would receive and measures them with its own OpenCV pass (peg
and hole positions, tilt, whether the peg's outline continues below the board line, i.e. is
inside the hole). Every robot-specific number comes from the request's `RobotDescription`; the
constants below are the rules' own proportions, the same for any robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import get_args

import cv2
import numpy as np

from kintsugi.core.errors import ReasoningError
from kintsugi.perception.segment import PerceptionConfig, board_surface_v, measure, peg_mask
from kintsugi.methods.recovery.types import AnalyzeRequest, JudgeRequest, RecoverySkill, SkillOutcome
from kintsugi.perception.types import CameraCalibration
from kintsugi.worlds.peg.description import RobotDescription

RECOVERY_ORDER: tuple[str, ...] = get_args(RecoverySkill)
"""Every skill in contact-formation order (approach, contact, fit, align, insert); a request's `skills` says
which a plan may use."""
HOLE_MARGIN_PX = 2.4
"""Slack, in pixels, when deciding whether the peg's cut outline lies inside the hole's opening."""
FIT_RELEASED_FRACTION = 0.5
"""A tip that sank into the hole relieves at least half the contact press; one caught on the rim keeps it."""
ALIGN_GAIN = 0.8
"""Fraction of the tilt correction to apply at once (the wrist absorbs part of any base motion)."""
PROBE_FRACTION = 0.75
"""A peg over the hole yet caught on a rim is probed sideways by this fraction of the clearance."""
TILT_RESOLUTION_DEG = 1.0
"""Tilts within this are measurement noise: the peg counts as upright."""
TILT_MARGIN_DEG = 0.5
"""A measured tilt must stay this far inside the task's tilt bound (about one pixel over the visible peg)."""


@dataclass(frozen=True)
class Seen:
    """What the embedded reasoner measures on one image (mm, degrees)."""

    peg: bool
    hole: bool
    peg_y: float = 0.0
    peg_edge_y: float = 0.0
    hole_y: float = 0.0
    tilt: float = 0.0
    in_hole: bool = False
    peg_top_z: float = 0.0
    tip_y: float = 0.0
    """Middle of the peg's bottom face (of its visible part, when the rest is in the hole)."""

    @property
    def offset(self) -> float:
        return self.peg_y - self.hole_y


def decode_png(png: bytes) -> np.ndarray:
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    if img is None:
        raise ValueError("image is not a decodable PNG")
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


def look(png: bytes | None, calib: CameraCalibration, cfg: PerceptionConfig) -> Seen:
    """Measure an image; `in_hole` = the peg's outline is cut wide by the board line, inside the opening."""
    if png is None:
        return Seen(peg=False, hole=False)
    rgb = decode_png(png)
    scene = measure(rgb, calib, cfg)
    if scene.peg is None or scene.hole is None:
        return Seen(peg=scene.peg is not None, hole=scene.hole is not None)
    mask = peg_mask(rgb, cfg) > 0
    v_surface = board_surface_v(rgb)
    in_hole = False
    if v_surface is not None and 0 <= int(v_surface) - 2 < mask.shape[0]:
        rows = mask.sum(axis=1)
        body = rows[rows > 0]
        cut = np.flatnonzero(mask[int(v_surface) - 2])
        if body.size and cut.size >= 0.5 * float(np.median(body)):
            # The outline continues below the board line over its full width: the peg is in the hole only
            # if that cut lies inside the opening (else it rests on the surface with a corner in the hole).
            left = calib.to_plane(float(cut[0]), v_surface)[0]
            right = calib.to_plane(float(cut[-1]) + 1.0, v_surface)[0]
            margin = HOLE_MARGIN_PX / calib.px_per_mm
            in_hole = left >= scene.hole.left_mm - margin and right <= scene.hole.right_mm + margin
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    box = cv2.boxPoints(cv2.minAreaRect(max(contours, key=cv2.contourArea)))
    bottom = box[np.argsort(box[:, 1])[-2:]].mean(axis=0)  # middle of the peg's bottom face
    tip_y = calib.to_plane(float(bottom[0]), float(bottom[1]))[0]
    p, h = scene.peg, scene.hole
    return Seen(peg=True, hole=True, peg_y=p.center_mm[0], peg_edge_y=p.edge_mm[0], hole_y=h.center_mm[0],
                tilt=p.tilt_deg, in_hole=bool(in_hole), peg_top_z=p.top_mm, tip_y=tip_y)


def robot_of(req: JudgeRequest | AnalyzeRequest) -> RobotDescription:
    if req.robot is None:
        raise ReasoningError("the embedded reasoner needs the robot's description (request.robot): its thresholds "
                             "come from the robot's own lever, wrist stiffness, contact press and vision settings")
    return req.robot


def fit_released(force_n: float, robot: RobotDescription) -> bool:
    """The wrist no longer feels most of the contact press: the tip has sunk past the surface."""
    return force_n <= FIT_RELEASED_FRACTION * max(robot.contact_press_n, 0.0)


def realign_shift(tilt_deg: float, robot: RobotDescription) -> float:
    """Base shift (mm) that turns a peg pivoting on its tip in the hole upright, damped by ALIGN_GAIN."""
    return ALIGN_GAIN * robot.compliance_to_tip_mm * math.tan(math.radians(tilt_deg))


def upright_enough(tilt_deg: float, robot: RobotDescription) -> bool:
    """Within the task's tilt bound, with the measurement's margin (and never stricter than upright)."""
    return abs(tilt_deg) <= max(robot.insert_max_tilt_deg - TILT_MARGIN_DEG, TILT_RESOLUTION_DEG)


def combined_tilt(main_deg: float, side_deg: float) -> float:
    """The axis's angle from vertical given its tilt seen in two perpendicular planes."""
    return math.degrees(math.atan(math.hypot(math.tan(math.radians(main_deg)), math.tan(math.radians(side_deg)))))


@dataclass(frozen=True)
class Approach:
    """The free-hanging peg against the approach goal image: how its tilt and its tip's place over the hole
    differ from when the goals were taught."""

    tilt_change: float
    """Peg tilt minus the goal image's (deg): the grasp holds the peg this much further over."""
    tip_shift: float
    """Tip-to-hole offset along y minus the goal image's (mm)."""
    base_shift: float
    """Base y change (mm) that puts the tip back where the goal image has it once the roll is turned back."""

    def ok(self, robot: RobotDescription, px_per_mm: float) -> bool:
        # The hole tolerates a tilt up to the task's bound and a shift up to its clearance.
        return (abs(self.tilt_change) <= robot.insert_max_tilt_deg
                and abs(self.tip_shift) <= max(robot.hole_clearance_mm, 2.0 / px_per_mm))


def compare_approach(out: SkillOutcome, goal_png: bytes | None, calib: CameraCalibration,
                     robot: RobotDescription) -> Approach | None:
    seen, goal = look(out.image_png, calib, robot.vision), look(goal_png, calib, robot.vision)
    if not (seen.peg and seen.hole and goal.peg and goal.hole):
        return None
    tip_shift = (seen.tip_y - seen.hole_y) - (goal.tip_y - goal.hole_y)
    # The peg hangs from the compliance centre: its tip sits lever * sin(tilt) to the right of it (tilt + =
    # top leaning left), so turning the tilt back to the goal image's also moves the tip by the difference.
    swing = robot.compliance_to_tip_mm * (math.sin(math.radians(goal.tilt)) - math.sin(math.radians(seen.tilt)))
    return Approach(tilt_change=seen.tilt - goal.tilt, tip_shift=tip_shift, base_shift=-tip_shift - swing)


@dataclass(frozen=True)
class Side:
    """What the side camera shows along x (mm, degrees): tip beside the hole, and the pitch."""

    tip_offset_x: float
    tilt: float


def look_side(req: JudgeRequest | AnalyzeRequest, cfg: PerceptionConfig) -> Side | None:
    """The side image, measured like the main one (its horizontal axis is x); None without one."""
    png, calib = req.outcome.side_image_png, req.side_calibration
    if png is None or calib is None:
        return None
    seen = look(png, calib, cfg)
    if not (seen.peg and seen.hole):
        return None
    return Side(tip_offset_x=seen.tip_y - seen.hole_y, tilt=seen.tilt)


def beside_along_x(side: Side, robot: RobotDescription, calib: CameraCalibration | None) -> bool:
    """The side camera shows the tip farther from the hole centre along x than the clearance lets it enter."""
    px = 1.0 / calib.px_per_mm if calib is not None else 0.0
    return abs(side.tip_offset_x) > robot.hole_clearance_mm / 2 + 2 * px


def tipping_lean_deg(robot: RobotDescription) -> float:
    """Lean beyond which a peg pressed down on its bottom edge tips sideways about that edge: the press acts
    at the compliance centre, and it passes outside the edge once tan(lean) > (width / 2) / lever."""
    return math.degrees(math.atan2(robot.peg_width_mm / 2, robot.compliance_to_tip_mm))
