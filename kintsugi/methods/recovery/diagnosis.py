"""The embedded peg reasoner's analyze and plan: what happened, why, how to recover, and the plan's goals.

Analysis reads the failed skill's image (and the side camera's, when sent) against the goal image
and states the recovery as motions relative to the current goals; the plan turns them into
absolute goals from the analysis's restart skill on. Same rules for any robot: the numbers come
from the request's `RobotDescription`.
"""

from __future__ import annotations

import math
from dataclasses import replace

from kintsugi.methods.recovery.seeing import (
    PROBE_FRACTION,
    RECOVERY_ORDER,
    TILT_RESOLUTION_DEG,
    Seen,
    Side,
    beside_along_x,
    compare_approach,
    fit_released,
    look,
    look_side,
    realign_shift,
    robot_of,
    tipping_lean_deg,
)
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    PlanReply,
    PlanRequest,
    PlanStep,
    RelativeMotion,
)
from kintsugi.worlds.peg.description import RobotDescription


def allowed_only(reply: AnalyzeReply, req: AnalyzeRequest) -> AnalyzeReply:
    """Keep to the skills this robot's recovery may use: drop other motions, restart at the first allowed skill."""
    if not req.skills:
        return reply
    motions = [m for m in reply.motions if m.skill in req.skills and m.axis in req.skills[m.skill]]
    later = [s for s in RECOVERY_ORDER[RECOVERY_ORDER.index(reply.restart_from):] if s in req.skills]
    restart = later[0] if later else next(s for s in RECOVERY_ORDER if s in req.skills)
    return reply.model_copy(update={"motions": motions, "restart_from": restart})


def analyze(req: AnalyzeRequest) -> AnalyzeReply:
    """The analyze role's embedded answer: what happened, why, and motions relative to the current goals."""
    return allowed_only(_analyze(req), req)


def _analyze(req: AnalyzeRequest) -> AnalyzeReply:
    robot = robot_of(req)
    skill = req.outcome.skill
    if skill == "approach":
        return _reapproach_after_approach(req, robot)
    seen = look(req.outcome.image_png, req.calibration, robot.vision)
    goal = look(req.goal_image_png, req.calibration, robot.vision)
    if skill == "fit" and not fit_released(req.outcome.wrist_force_z_n, robot):
        seen = replace(seen, in_hole=False)  # still pressed: the tip has not sunk in (see judge)
    want = goal.offset if (goal.peg and goal.hole) else 0.0  # taught peg-to-hole offset for this skill
    if not (seen.peg and seen.hole):
        return _reply(skill, "the camera could not see the peg and the hole", "unknown", skill, [])
    side = look_side(req, robot.vision)
    state = (f"peg centre {seen.offset:+.1f} mm from the hole centre (taught: {want:+.1f} mm), peg tip "
             f"{seen.tip_y - seen.hole_y:+.1f} mm from it, tilt "
             f"{seen.tilt:+.1f} deg, tip {'inside' if seen.in_hole else 'outside'} the hole")
    if side is not None:
        state += (f"; side camera: tip {side.tip_offset_x:+.1f} mm from the hole centre along x, pitch "
                  f"{side.tilt:+.1f} deg")
    if "approach" in req.skills and side is not None and beside_along_x(side, robot, req.side_calibration):
        return _lean_less(skill, seen, side, state, robot, req)
    if skill == "fit" or not seen.in_hole:
        tries = sum(1 for a in req.history if a.skill == "fit" and not a.success)
        return _refit(skill, seen, want if skill == "fit" else None, state, tries, robot, req)
    return _realign(skill, seen, state, robot)


def _reapproach_after_approach(req: AnalyzeRequest, robot: RobotDescription) -> AnalyzeReply:
    """The hanging peg is tilted unlike the goal image (the grasp angle) or the hole moved: approach again
    with the roll turned back by the tilt change and every y goal moved with the hole."""
    change = compare_approach(req.outcome, req.goal_image_png, req.calibration, robot)
    if change is None:
        return _reply("approach", "the camera could not see the peg and the hole", "unknown", "approach", [])
    state = (f"the hanging peg is tilted {change.tilt_change:+.1f} deg and its tip lies {change.tip_shift:+.1f} "
             f"mm along y from where the goal image shows them, relative to the hole")
    # Image tilt + is the top leaning left, which a + roll of the base also gives: turn the roll back by it.
    # Every y goal moves with the hole, so contact, fit and align meet it as they were taught.
    motions = [("approach", "roll", -change.tilt_change)]
    motions += [(s, "y", change.base_shift) for s in ("approach", "fit", "align")]
    why = "the grasp holds the peg at another angle than when the goals were taught, or the hole is elsewhere"
    return _reapproach("approach", state, why, motions, req)


def _reapproach(skill: str, state: str, why: str, motions: list[tuple[str, str, float]],
                req: AnalyzeRequest) -> AnalyzeReply:
    kept = [RelativeMotion(skill=s, axis=a, delta=round(d, 2)) for s, a, d in motions
            if s in req.skills and a in req.skills[s] and abs(d) >= 0.01]
    how = ("lift the peg and approach again" + (", moving " + ", ".join(
        f"{m.skill} {m.axis} {m.delta:+.1f}" for m in kept) if kept else "") + "; then contact, fit, align, insert")
    return _reply(skill, state, why, "approach", kept, how)


def _lean_less(skill: str, seen: Seen, side: Side, state: str, robot: RobotDescription,
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
    return _reapproach(skill, state, why, motions, req)


def _refit(skill: str, seen: Seen, want: float | None, state: str, tries: int,
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
    return _reply(skill, state, why, "fit", motions, how)


def _realign(skill: str, seen: Seen, state: str, robot: RobotDescription) -> AnalyzeReply:
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
    return _reply(skill, state, why, "align", motions, how)


def _reply(skill: str, state: str, why: str, restart: str, motions: list[RelativeMotion],
           how: str = "repeat the skill") -> AnalyzeReply:
    return AnalyzeReply(what_happened=f"{skill} failed: {state}.", why=why, how_to_recover=how,
                        restart_from=restart, motions=motions)


def plan(req: PlanRequest) -> PlanReply:
    """The plan role's embedded answer: absolute goals from the analysis's restart skill on (unclamped)."""
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
