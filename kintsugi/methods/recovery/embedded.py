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
from typing import get_args

import cv2
import numpy as np

from kintsugi.core.errors import ReasoningError
from kintsugi.perception.segment import PerceptionConfig, board_surface_v, measure, peg_mask
from kintsugi.reasoning import REASONERS
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    CameraCalibration,
    JudgeReply,
    JudgeRequest,
    PlanReply,
    PlanRequest,
    PlanStep,
    RecoverySkill,
    RelativeMotion,
    RobotDescription,
    SkillOutcome,
)
from kintsugi.core.record import ReasonerSettings

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


def allowed_only(reply: AnalyzeReply, req: AnalyzeRequest) -> AnalyzeReply:
    """Keep to the skills this robot's recovery may use: drop other motions, restart at the first allowed skill."""
    if not req.skills:
        return reply
    motions = [m for m in reply.motions if m.skill in req.skills and m.axis in req.skills[m.skill]]
    later = [s for s in RECOVERY_ORDER[RECOVERY_ORDER.index(reply.restart_from):] if s in req.skills]
    restart = later[0] if later else next(s for s in RECOVERY_ORDER if s in req.skills)
    return reply.model_copy(update={"motions": motions, "restart_from": restart})


def beside_along_x(side: Side, robot: RobotDescription, calib: CameraCalibration | None) -> bool:
    """The side camera shows the tip farther from the hole centre along x than the clearance lets it enter."""
    px = 1.0 / calib.px_per_mm if calib is not None else 0.0
    return abs(side.tip_offset_x) > robot.hole_clearance_mm / 2 + 2 * px


def tipping_lean_deg(robot: RobotDescription) -> float:
    """Lean beyond which a peg pressed down on its bottom edge tips sideways about that edge: the press acts
    at the compliance centre, and it passes outside the edge once tan(lean) > (width / 2) / lever."""
    return math.degrees(math.atan2(robot.peg_width_mm / 2, robot.compliance_to_tip_mm))


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
        if out.skill == "approach":
            return self._judge_approach(req, robot)
        seen = look(out.image_png, req.calibration, cfg)
        if not (seen.peg and seen.hole):
            return JudgeReply(success=False, explanation="The camera cannot see both the peg and the hole.")
        side = look_side(req, cfg)
        where = f"peg centre {seen.offset:+.1f} mm from the hole centre, tilt {seen.tilt:+.1f} deg"
        if side is not None:
            where += f"; side camera: tip {side.tip_offset_x:+.1f} mm from the hole centre along x, pitch " \
                     f"{side.tilt:+.1f} deg"
        if out.skill == "fit":
            vision = checks.get("vision_fit")
            table = vision.message if vision else "no vision check"
            if seen.in_hole and not fit_released(out.wrist_force_z_n, robot):
                return JudgeReply(success=False, explanation=(
                    f"Fit failed: the peg's outline dips below the board line, but the wrist still presses with "
                    f"{out.wrist_force_z_n:.1f} N of the {robot.contact_press_n:.1f} N contact press, so the tip has "
                    f"not sunk into the hole ({where})."))
            if seen.in_hole and side is not None and beside_along_x(side, robot, req.side_calibration):
                return JudgeReply(success=False, explanation=(
                    f"Fit failed: the main camera sees the tip below the board line, but the side camera shows it "
                    f"resting beside the opening along x, out of the main camera's plane ({where})."))
            if seen.in_hole:  # the formation's purpose; align corrects any residual offset or tilt
                note = "" if vision and vision.passed else f" (Table I says '{table}'; align will correct it)"
                return JudgeReply(success=True, explanation=(
                    f"Fit succeeded: the peg's outline is cut by the board line, so its tip is in the hole{note} "
                    f"({where})."))
            return JudgeReply(success=False, explanation=(
                f"Fit failed: the peg's outline ends on the board surface, so the tip is not in the hole "
                f"(Table I: '{table}'; {where})."))
        tilt = seen.tilt if side is None else combined_tilt(seen.tilt, side.tilt)
        if out.skill == "align":
            vision = checks.get("vision_align")
            ok = bool(vision and vision.passed) and seen.in_hole
            why = (vision.message if vision and not vision.passed else
                   "the peg has left the hole" if not seen.in_hole else
                   "the side camera shows the tip beside the opening along x"
                   if side is not None and beside_along_x(side, robot, req.side_calibration) else f"the peg leans {tilt:.1f} deg, not clearly within the {robot.insert_max_tilt_deg:.1f} deg "
                        f"the hole lets an inserted peg lean" if not upright_enough(tilt, robot)
                   else "the peg is upright over the hole")
            ok = (ok and (side is None or not beside_along_x(side, robot, req.side_calibration))
                  and upright_enough(tilt, robot))
            return JudgeReply(success=ok, explanation=f"Align {'succeeded' if ok else 'failed'}: {why} ({where}).")
        image = checks.get("insert_image")
        if image is None:
            return JudgeReply(success=False, explanation="Insert failed: no goal-image comparison was given.")
        diff = image.measurements.get("top_difference_mm", float("inf"))
        deep = abs(diff) <= cfg.insert_top_tol_mm
        centred = abs(seen.offset) <= cfg.align_tol_mm + robot.hole_clearance_mm
        upright = upright_enough(tilt, robot)
        ok = deep and seen.in_hole and centred and upright
        if ok:
            why = (f"the peg stands as low as in the goal image (top {diff:+.1f} mm from it), is centred on the "
                   f"hole and leans {tilt:.1f} deg, within the task's {robot.insert_max_tilt_deg:.1f} deg ({where})")
            if not image.passed:
                why += "; the image comparison's position mismatch only reflects where this hole is"
        elif not deep:
            why = image.message
        elif not (seen.in_hole and centred):
            why = f"the peg is not centred in the hole ({where})"
        else:
            why = (f"the peg leans {tilt:.1f} deg, not clearly within the task's {robot.insert_max_tilt_deg:.1f} deg "
                   f"(the measurement keeps a {TILT_MARGIN_DEG:g} deg margin): it may be wedged in the hole, not "
                   f"inserted ({where})")
        return JudgeReply(success=ok, explanation=f"Insert {'succeeded' if ok else 'failed'}: {why}")

    def _judge_approach(self, req: JudgeRequest, robot: RobotDescription) -> JudgeReply:
        change = compare_approach(req.outcome, req.goal_image_png, req.calibration, robot)
        if change is None:
            return JudgeReply(success=False, explanation="The camera cannot see the peg and the hole in this image "
                                                         "and the goal image.")
        ok = change.ok(robot, req.calibration.px_per_mm)
        return JudgeReply(success=ok, explanation=(
            f"Approach {'succeeded' if ok else 'failed'}: the hanging peg is tilted {change.tilt_change:+.1f} deg "
            f"and its tip lies {change.tip_shift:+.1f} mm along y from where the goal image shows them, relative "
            f"to the hole "
            f"({'within' if ok else 'beyond'} the {robot.insert_max_tilt_deg:.1f} deg and "
            f"{robot.hole_clearance_mm:g} mm the hole tolerates)."))

    # --- analyze: what happened, why, how to recover ---------------------
    def analyze(self, req: AnalyzeRequest) -> AnalyzeReply:
        return allowed_only(self._analyze(req), req)

    def _analyze(self, req: AnalyzeRequest) -> AnalyzeReply:
        robot = robot_of(req)
        skill = req.outcome.skill
        if skill == "approach":
            return self._reapproach_after_approach(req, robot)
        seen = look(req.outcome.image_png, req.calibration, robot.vision)
        goal = look(req.goal_image_png, req.calibration, robot.vision)
        if skill == "fit" and not fit_released(req.outcome.wrist_force_z_n, robot):
            seen = replace(seen, in_hole=False)  # still pressed: the tip has not sunk in (see judge)
        want = goal.offset if (goal.peg and goal.hole) else 0.0  # taught peg-to-hole offset for this skill
        if not (seen.peg and seen.hole):
            return self._reply(skill, "the camera could not see the peg and the hole", "unknown", skill, [])
        side = look_side(req, robot.vision)
        state = (f"peg centre {seen.offset:+.1f} mm from the hole centre (taught: {want:+.1f} mm), peg tip "
                 f"{seen.tip_y - seen.hole_y:+.1f} mm from it, tilt "
                 f"{seen.tilt:+.1f} deg, tip {'inside' if seen.in_hole else 'outside'} the hole")
        if side is not None:
            state += (f"; side camera: tip {side.tip_offset_x:+.1f} mm from the hole centre along x, pitch "
                      f"{side.tilt:+.1f} deg")
        if "approach" in req.skills and side is not None and beside_along_x(side, robot, req.side_calibration):
            return self._lean_less(skill, seen, side, state, robot, req)
        if skill == "fit" or not seen.in_hole:
            tries = sum(1 for a in req.history if a.skill == "fit" and not a.success)
            return self._refit(skill, seen, want if skill == "fit" else None, state, tries, robot, req)
        return self._realign(skill, seen, state, robot)

    def _reapproach_after_approach(self, req: AnalyzeRequest, robot: RobotDescription) -> AnalyzeReply:
        """The hanging peg is tilted unlike the goal image (the grasp angle) or the hole moved: approach again
        with the roll turned back by the tilt change and every y goal moved with the hole."""
        change = compare_approach(req.outcome, req.goal_image_png, req.calibration, robot)
        if change is None:
            return self._reply("approach", "the camera could not see the peg and the hole", "unknown", "approach", [])
        state = (f"the hanging peg is tilted {change.tilt_change:+.1f} deg and its tip lies {change.tip_shift:+.1f} "
                 f"mm along y from where the goal image shows them, relative to the hole")
        # Image tilt + is the top leaning left, which a + roll of the base also gives: turn the roll back by it.
        # Every y goal moves with the hole, so contact, fit and align meet it as they were taught.
        motions = [("approach", "roll", -change.tilt_change)]
        motions += [(s, "y", change.base_shift) for s in ("approach", "fit", "align")]
        why = "the grasp holds the peg at another angle than when the goals were taught, or the hole is elsewhere"
        return self._reapproach("approach", state, why, motions, req)

    def _reapproach(self, skill: str, state: str, why: str, motions: list[tuple[str, str, float]],
                    req: AnalyzeRequest) -> AnalyzeReply:
        kept = [RelativeMotion(skill=s, axis=a, delta=round(d, 2)) for s, a, d in motions
                if s in req.skills and a in req.skills[s] and abs(d) >= 0.01]
        how = ("lift the peg and approach again" + (", moving " + ", ".join(
            f"{m.skill} {m.axis} {m.delta:+.1f}" for m in kept) if kept else "") + "; then contact, fit, align, insert")
        return self._reply(skill, state, why, "approach", kept, how)

    def _lean_less(self, skill: str, seen: Seen, side: Side, state: str, robot: RobotDescription,
                   req: AnalyzeRequest) -> AnalyzeReply:
        """The side camera shows the tip beside the opening along x: pressed on its bottom edge while leaning
        further than that edge can carry, the peg tipped sideways on the soft pitch joint, out of the main
        camera's plane. Approach again leaning less (below the tipping lean, by the roll), with every y goal
        moved so the tip still meets the hole where it was taught."""
        limit = tipping_lean_deg(robot)
        lean_change = -(max(abs(seen.tilt) - limit, 0.0) + TILT_RESOLUTION_DEG) * math.copysign(1.0, seen.tilt)
        lever = robot.compliance_to_tip_mm
        tip_move = lever * (math.sin(math.radians(seen.tilt + lean_change)) - math.sin(math.radians(seen.tilt)))
        motions = [("approach", "roll", lean_change)] + [(s, "y", -tip_move) for s in ("approach", "fit", "align")]
        why = (f"the peg leans {seen.tilt:+.1f} deg on its bottom edge, beyond the {limit:.1f} deg (atan of half its "
               f"width over the {lever:g} mm lever) at which the wrist's press tips it sideways: it swung "
               f"{side.tip_offset_x:+.1f} mm out of the main camera's plane (pitch {side.tilt:+.1f} deg)")
        return self._reapproach(skill, state, why, motions, req)

    def _refit(self, skill: str, seen: Seen, want: float | None, state: str, tries: int,
               robot: RobotDescription, req: AnalyzeRequest) -> AnalyzeReply:
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
