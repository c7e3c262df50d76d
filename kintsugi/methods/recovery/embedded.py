"""The embedded peg reasoner: deterministic, offline, and limited to what a VLM would see.

It decodes the same PNGs a model would receive, measures them with its own
OpenCV pass (peg/hole positions, tilt, whether the peg's outline continues
below the board line, i.e. is inside the hole), reads the check messages and
the robot's poses and wrist force, and answers each role with rules a person
would apply looking at the picture. It never touches the simulator.

Every robot-specific number comes from the request's `RobotDescription` (the
robot's own build config and vision settings): the lever that turns a base
shift into a tilt, the contact press a sunk tip relieves, the hole clearance
and the check tolerances; the rules' own proportions (in `seeing`) are the
same for any robot.

This module holds the judge (`judge`); `diagnosis` holds analyze and plan,
`seeing` the image measurements they share. `roles` registers all three.
"""

from __future__ import annotations

from kintsugi.methods.recovery.diagnosis import allowed_only, analyze, plan  # noqa: F401 - the other two roles
from kintsugi.methods.recovery.seeing import (  # noqa: F401 - re-exported: the rules' measurements and proportions
    ALIGN_GAIN,
    FIT_RELEASED_FRACTION,
    HOLE_MARGIN_PX,
    PROBE_FRACTION,
    RECOVERY_ORDER,
    TILT_MARGIN_DEG,
    TILT_RESOLUTION_DEG,
    Approach,
    Seen,
    Side,
    beside_along_x,
    combined_tilt,
    compare_approach,
    decode_png,
    fit_released,
    look,
    look_side,
    realign_shift,
    robot_of,
    tipping_lean_deg,
    upright_enough,
)
from kintsugi.methods.recovery.types import JudgeReply, JudgeRequest
from kintsugi.worlds.peg.description import RobotDescription


def judge(req: JudgeRequest) -> JudgeReply:
    """The judge role's embedded answer: the checks, the wrist force and the images fused into one verdict."""
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
        return _judge_approach(req, robot)
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


def _judge_approach(req: JudgeRequest, robot: RobotDescription) -> JudgeReply:
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
