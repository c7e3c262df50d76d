"""The embedded reasoner: deterministic, offline, and limited to what a VLM would see.

It decodes the same PNGs a model would receive, measures them with its own
OpenCV pass (peg/hole positions, tilt, whether the peg's outline continues
below the board line, i.e. is inside the hole), reads the check messages and
the robot's poses and wrist force, and answers each role with rules a person
would apply looking at the picture. It never touches the simulator.

Every robot-specific number comes from the request's `RobotDescription` (the
robot's own build config and vision settings): the lever that turns a base
shift into a tilt, the contact press a sunk tip relieves, the hole clearance
and the check tolerances. The constants below are the rules' own
proportions, the same for any robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from kintsugi.errors import ReasoningError
from kintsugi.perception.segment import PerceptionConfig, board_surface_v, measure, peg_mask
from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.types import (
    AnalyzeReply,
    AnalyzeRequest,
    CameraCalibration,
    JudgeReply,
    JudgeRequest,
    PlanReply,
    PlanRequest,
    PlanStep,
    RelativeMotion,
    RobotDescription,
)
from kintsugi.trial import ReasonerSettings

RECOVERY_ORDER = ("fit", "align", "insert")
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


class EmbeddedReasoner:
    name = "embedded"

    def __init__(self) -> None:
        self.last_stats = None

    # --- judge: fuse the checks into one verdict -----------------------
    def judge(self, req: JudgeRequest) -> JudgeReply:
        robot = robot_of(req)
        cfg = robot.vision
        checks = {c.name: c for c in req.checks}
        out = req.outcome
        if out.compression_limit:
            return JudgeReply(success=False, explanation=(
                f"The wrist hit its compression limit ({out.wrist_force_z_n:.1f} N): the peg is blocked, "
                f"so {out.skill} failed whatever the image shows."))
        if "pose" in checks and not checks["pose"].passed:
            return JudgeReply(success=False, explanation=f"The arm did not reach its goal: {checks['pose'].message}")
        seen = look(out.image_png, req.calibration, cfg)
        if not (seen.peg and seen.hole):
            return JudgeReply(success=False, explanation="The camera cannot see both the peg and the hole.")
        where = f"peg centre {seen.offset:+.1f} mm from the hole centre, tilt {seen.tilt:+.1f} deg"
        if out.skill == "fit":
            vision = checks.get("vision_fit")
            table = vision.message if vision else "no vision check"
            if seen.in_hole and not fit_released(out.wrist_force_z_n, robot):
                return JudgeReply(success=False, explanation=(
                    f"Fit failed: the peg's outline dips below the board line, but the wrist still presses with "
                    f"{out.wrist_force_z_n:.1f} N of the {robot.contact_press_n:.1f} N contact press, so the tip has "
                    f"not sunk into the hole ({where})."))
            if seen.in_hole:  # the formation's purpose; align corrects any residual offset or tilt
                note = "" if vision and vision.passed else f" (Table I says '{table}'; align will correct it)"
                return JudgeReply(success=True, explanation=(
                    f"Fit succeeded: the peg's outline is cut by the board line, so its tip is in the hole{note} "
                    f"({where})."))
            return JudgeReply(success=False, explanation=(
                f"Fit failed: the peg's outline ends on the board surface, so the tip is not in the hole "
                f"(Table I: '{table}'; {where})."))
        if out.skill == "align":
            vision = checks.get("vision_align")
            ok = bool(vision and vision.passed) and seen.in_hole
            why = (vision.message if vision and not vision.passed else
                   "the peg is upright over the hole" if ok else "the peg has left the hole")
            return JudgeReply(success=ok, explanation=f"Align {'succeeded' if ok else 'failed'}: {why} ({where}).")
        image = checks.get("insert_image")
        if image is None:
            return JudgeReply(success=False, explanation="Insert failed: no goal-image comparison was given.")
        diff = image.measurements.get("top_difference_mm", float("inf"))
        deep = abs(diff) <= cfg.insert_top_tol_mm
        centred = abs(seen.offset) <= cfg.align_tol_mm + robot.hole_clearance_mm
        ok = deep and seen.in_hole and centred
        if ok:
            why = (f"the peg stands as low as in the goal image (top {diff:+.1f} mm from it) and is centred on the "
                   f"hole ({where})")
            if not image.passed:
                why += "; the image comparison's position mismatch only reflects where this hole is"
        else:
            why = image.message if not deep else f"the peg is not centred in the hole ({where})"
        return JudgeReply(success=ok, explanation=f"Insert {'succeeded' if ok else 'failed'}: {why}")

    # --- analyze: what happened, why, how to recover ---------------------
    def analyze(self, req: AnalyzeRequest) -> AnalyzeReply:
        robot = robot_of(req)
        seen = look(req.outcome.image_png, req.calibration, robot.vision)
        goal = look(req.goal_image_png, req.calibration, robot.vision)
        skill = req.outcome.skill
        if skill == "fit" and not fit_released(req.outcome.wrist_force_z_n, robot):
            seen = replace(seen, in_hole=False)  # still pressed: the tip has not sunk in (see judge)
        want = goal.offset if (goal.peg and goal.hole) else 0.0  # taught peg-to-hole offset for this skill
        if not (seen.peg and seen.hole):
            return self._reply(skill, "the camera could not see the peg and the hole", "unknown",
                               skill if skill in RECOVERY_ORDER else "fit", [])
        state = (f"peg centre {seen.offset:+.1f} mm from the hole centre (taught: {want:+.1f} mm), peg tip "
                 f"{seen.tip_y - seen.hole_y:+.1f} mm from it, tilt "
                 f"{seen.tilt:+.1f} deg, tip {'inside' if seen.in_hole else 'outside'} the hole")
        if skill == "fit" or not seen.in_hole:
            tries = sum(1 for a in req.history if a.skill == "fit" and not a.success)
            return self._refit(skill, seen, want if skill == "fit" else None, state, tries, robot)
        return self._realign(skill, seen, state, robot)

    def _refit(self, skill: str, seen: Seen, want: float | None, state: str, tries: int,
               robot: RobotDescription) -> AnalyzeReply:
        """The tip is not (or not properly) in the hole: slide again so the tip sits over the hole."""
        clearance = robot.hole_clearance_mm
        if seen.in_hole and want is not None:  # in, but the centre passed the hole centre: back to its near side
            shift = min(want - seen.offset, -seen.offset - clearance)
        else:
            shift = seen.hole_y - seen.tip_y  # centre the tip over the opening, where it drops in
            if abs(shift) < clearance / 2:  # over the hole yet caught on a rim: probe either side, alternately
                probe = PROBE_FRACTION * clearance
                shift = probe if tries % 2 == 0 else -probe
        why = ("the fit goal does not match where the hole is (hole pose error, grasp angle or friction drag)"
               if skill == "fit" else f"the peg slipped out of the hole during {skill}")
        how = f"run fit again with its y goal moved {shift:+.1f} mm, then align (same shift) and insert"
        motions = [RelativeMotion(skill="fit", axis="y", delta=round(shift, 2)),
                   RelativeMotion(skill="align", axis="y", delta=round(shift, 2))]
        return self._reply(skill, state, why, "fit", motions, how)

    def _realign(self, skill: str, seen: Seen, state: str, robot: RobotDescription) -> AnalyzeReply:
        """Tip in the hole: rotate the peg upright and centre it by moving the align goal."""
        tilted = abs(seen.tilt) > TILT_RESOLUTION_DEG
        # In the hole the peg can only pivot: its visible centre's offset follows from its tilt,
        # so the tilt decides; only an upright peg is re-centred.
        shift = realign_shift(seen.tilt, robot) if tilted else -seen.offset
        if abs(shift) < robot.hole_clearance_mm / 2:  # looks aligned yet failed: nudge toward upright
            probe = PROBE_FRACTION * robot.hole_clearance_mm
            shift = probe if seen.tilt >= 0 else -probe
        why = "the peg is still tilted in the hole" if tilted else "the peg is off the hole centre"
        if skill == "insert":
            why = f"insertion jammed: {why}"
        how = f"move the align goal {shift:+.1f} mm in y, then insert again"
        motions = [RelativeMotion(skill="align", axis="y", delta=round(shift, 2))]
        return self._reply(skill, state, why, "align", motions, how)

    @staticmethod
    def _reply(skill: str, state: str, why: str, restart: str, motions: list[RelativeMotion],
               how: str = "repeat the skill") -> AnalyzeReply:
        return AnalyzeReply(what_happened=f"{skill} failed: {state}.", why=why, how_to_recover=how,
                            restart_from=restart, motions=motions)

    # --- plan: absolute goals from the analysis -------------------------
    def plan(self, req: PlanRequest) -> PlanReply:
        start = RECOVERY_ORDER.index(req.analysis.restart_from)
        steps = []
        for skill in RECOVERY_ORDER[start:]:
            if skill not in req.skills:
                continue
            current = req.goals[skill]
            goal = {}
            for axis in req.skills[skill]:
                delta = sum(m.delta for m in req.analysis.motions if m.skill == skill and m.axis == axis)
                goal[axis] = round(getattr(current, axis) + delta, 3)
            steps.append(PlanStep(skill=skill, goal=goal))
        return PlanReply(steps=steps)


@REASONERS.register("embedded", "deterministic offline reasoner: OpenCV on the images + rules, no model",
                    tags=("offline",))
def make_embedded(settings: ReasonerSettings) -> EmbeddedReasoner:
    return EmbeddedReasoner()
