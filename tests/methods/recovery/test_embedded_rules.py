"""The embedded reasoner's decision rules, on frames rendered live by the real world.

Each frame comes from running the taught skills in a world whose hole is moved
(as a `pose` trial would), so the peg ends in the hole, beside it or jammed.
Requests are built as the recovery method builds them, with the robot's own
description. Ground truth is read here only to state what the right answer is.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import lru_cache

os.environ.setdefault("MUJOCO_GL", "egl")  # headless; must precede the first `import mujoco`

import pytest

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ReasoningError
from kintsugi.methods.recovery.method import to_png
from kintsugi.methods.recovery import embedded
from kintsugi.methods.recovery.embedded import ALIGN_GAIN, fit_released, look, realign_shift
from kintsugi.methods.recovery.types import AnalyzeRequest, JudgeReply, JudgeRequest, SkillOutcome
from kintsugi.perception.types import CameraCalibration, CheckResult, HsvRange
from kintsugi.worlds.peg.description import RobotDescription
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import full_goals, load_goals
from kintsugi.worlds.peg.robot import describe_robot, to_pose
from kintsugi.worlds.peg.skills import execute_skill
from kintsugi.worlds.peg.world import HOME_POSE, GroundTruth, PegWorld, TrialParams

GOALS = load_goals()
REASONER = embedded  # the embedded answers: judge(request), analyze(request), plan(request)


@dataclass(frozen=True)
class Frame:
    """The state after a skill: what the robot saw and felt, and (for the test only) the truth."""

    skill: str
    goal_y_mm: float
    png: bytes
    calibration: CameraCalibration
    force_n: float
    truth: GroundTruth

    def outcome(self, force_n: float | None = None) -> SkillOutcome:
        pose = to_pose(full_goals(GOALS, HOME_POSE)[self.skill])
        pose = pose.model_copy(update={"y": self.goal_y_mm})
        return SkillOutcome(skill=self.skill, goal=pose, terminal=pose, reached_goal=True, timed_out=False,
                            compression_limit=False, wrist_force_z_n=self.force_n if force_n is None else force_n,
                            image_png=self.png)


def config(*overrides: str) -> PegTaskConfig:
    return apply_overrides(PegTaskConfig(), list(overrides))


@lru_cache(maxsize=None)
def frame(shape: str, hole_y: float, upto: str = "fit", overrides: tuple[str, ...] = (),
          align_y: float | None = None) -> Frame:
    """Run approach..`upto` with the taught goals (align y replaced by `align_y` if given)."""
    cfg = config(*overrides)
    world = PegWorld(cfg, TrialParams(shape=shape, hole_y_mm=hole_y))
    try:
        targets = full_goals(GOALS, HOME_POSE)
        for skill in ("approach", "contact", "fit", "align"):
            goal = targets[skill].copy()
            if skill == "align" and align_y is not None:
                goal[0] = align_y / 1000
            result = execute_skill(world, skill, goal)
            if skill == upto:
                break
        return Frame(skill=upto, goal_y_mm=float(goal[0]) * 1000, png=to_png(result.image),
                     calibration=world.calibration(), force_n=world.wrist_compression() * cfg.wrist.z_stiffness,
                     truth=world.ground_truth())
    finally:
        world.close()


def robot(shape: str, *overrides: str) -> RobotDescription:
    return describe_robot(config(*overrides), shape, GOALS)


def judge(f: Frame, desc: RobotDescription, force_n: float | None = None) -> JudgeReply:
    return REASONER.judge(JudgeRequest(task="insert", outcome=f.outcome(force_n), checks=[], success_criteria="-",
                                       calibration=f.calibration, robot=desc))


# --- tip in the hole -------------------------------------------------------

@pytest.mark.parametrize(("shape", "hole_y", "in_hole"), [
    ("round", 12.0, True),    # the tip dropped in near the left wall, peg tilted
    ("square", -16.0, True),  # hole to the left: the fit slide overshoots, the peg leans the other way
    ("round", 18.0, False),   # the hole is beyond the fit goal: the tip rests on the surface
    ("round", -16.0, False),  # dragged over the near rim and tipped: a corner is past the board line
])
def test_tip_in_hole_matches_the_truth(shape: str, hole_y: float, in_hole: bool) -> None:
    f = frame(shape, hole_y)
    assert (f.truth.inside_hole and f.truth.tip_depth_mm > 1.0) is in_hole  # the scenario is what it claims
    assert look(f.png, f.calibration, robot(shape).vision).in_hole is in_hole
    verdict = judge(f, robot(shape))
    assert verdict.success is (in_hole and fit_released(f.force_n, robot(shape)))


# --- fit released: a fraction of the robot's own contact press ---------------

def test_contact_press_follows_the_robot_description() -> None:
    default, stiff = robot("round"), robot("round", "wrist.z_stiffness=2000")
    assert default.contact_press_mm == pytest.approx(11.0, abs=0.1)  # taught contact z vs the tilted peg's corner
    assert stiff.contact_press_mm == default.contact_press_mm
    assert stiff.contact_press_n == pytest.approx(2 * default.contact_press_n)
    longer = robot("round", "wrist.hinge_to_grasp_mm=50")
    assert longer.contact_press_mm == pytest.approx(default.contact_press_mm + 10 * math.cos(math.radians(8)), abs=0.01)


def test_fit_released_scales_with_the_contact_press() -> None:
    f = frame("round", 12.0)  # tip in the hole
    default, stiff = robot("round"), robot("round", "wrist.z_stiffness=2000")
    assert judge(f, default, force_n=0.3 * default.contact_press_n).success
    pressed = judge(f, default, force_n=0.7 * default.contact_press_n)
    assert not pressed.success and "still presses" in pressed.explanation
    # 8 N is most of the press of a 1 N/mm wrist, but little of a 2 N/mm wrist's.
    assert not judge(f, default, force_n=8.0).success
    assert judge(f, stiff, force_n=8.0).success


@pytest.mark.parametrize(("stiffness", "shape", "hole_y", "sunk"), [
    (1000, "round", 12.0, True),
    (1000, "square", 16.0, False),  # tip 2.4 mm in, jammed on the far edge: the wrist keeps 6 N of 11 N
    (2000, "square", 16.0, True),
    (2000, "square", 15.0, False),  # same jam on a stiffer wrist: 13 N of 22 N
])
def test_fit_judge_on_real_presses(stiffness: int, shape: str, hole_y: float, sunk: bool) -> None:
    overrides = (f"wrist.z_stiffness={stiffness}",)
    f = frame(shape, hole_y, overrides=overrides)
    assert (f.truth.tip_depth_mm > 5.0) is sunk and f.truth.inside_hole
    assert judge(f, robot(shape, *overrides)).success is sunk


# --- realign: sign and gain, closed through the physics ----------------------

@pytest.mark.parametrize("hole_y", [12.0, -12.0])
def test_realign_turns_the_peg_upright(hole_y: float) -> None:
    taught_align = GOALS["align"]["y"]
    desc = robot("round")
    f = frame("round", hole_y, upto="align")
    seen = look(f.png, f.calibration, desc.vision)
    assert seen.in_hole and abs(seen.tilt) > 4.0
    reply = REASONER.analyze(AnalyzeRequest(
        task="insert", outcome=f.outcome(), checks=[], verdict=JudgeReply(success=False, explanation="tilted"),
        goals={}, history=[], calibration=f.calibration, max_step_mm=10.0, robot=desc))
    assert reply.restart_from == "align"
    (motion,) = reply.motions
    assert (motion.skill, motion.axis) == ("align", "y")
    assert math.copysign(1, motion.delta) == math.copysign(1, seen.tilt)  # top leans left (+) -> move right (+y)
    expected = ALIGN_GAIN * desc.compliance_to_tip_mm * math.tan(math.radians(seen.tilt))
    assert motion.delta == pytest.approx(expected, abs=0.01)
    step = max(-10.0, min(10.0, motion.delta))  # as the plan validator clamps it
    after = frame("round", hole_y, upto="align", align_y=taught_align + step)
    assert abs(after.truth.tilt_deg) < 0.5 * abs(f.truth.tilt_deg)
    assert after.truth.inside_hole


def test_realign_gain_follows_the_lever() -> None:
    short, long_ = robot("round"), robot("round", "wrist.hinge_to_grasp_mm=90")
    assert long_.compliance_to_tip_mm == short.compliance_to_tip_mm + 50
    assert realign_shift(5.0, long_) / realign_shift(5.0, short) == pytest.approx(190 / 140)
    assert realign_shift(-5.0, short) == -realign_shift(5.0, short)


# --- the reasoner follows --set perception.* and needs the description --------

def test_reasoner_sees_with_the_configured_perception() -> None:
    f = frame("round", 12.0)
    assert judge(f, robot("round")).success
    green_only = '[{"lower":[40,90,40],"upper":[70,255,255]}]'
    blind = judge(f, robot("round", f"perception.peg_hsv={green_only}"))
    assert not blind.success and "cannot see" in blind.explanation
    assert robot("round", f"perception.peg_hsv={green_only}").vision.peg_hsv == [
        HsvRange(lower=(40, 90, 40), upper=(70, 255, 255))]


def test_insert_depth_tolerance_comes_from_perception() -> None:
    goal = frame("round", 0.0, upto="align")  # upright in the hole, as after a good insert's approach
    check = CheckResult(name="insert_image", passed=True, message="-", measurements={"top_difference_mm": 2.0})

    def verdict(*overrides: str) -> bool:
        req = JudgeRequest(task="insert", outcome=goal.outcome().model_copy(update={"skill": "insert"}),
                           checks=[check], success_criteria="-", calibration=goal.calibration,
                           robot=robot("round", *overrides))
        return REASONER.judge(req).success

    assert verdict()  # 2 mm within the default 3 mm
    assert not verdict("perception.insert_top_tol_mm=1")


def test_missing_robot_description_is_a_reasoning_error() -> None:
    f = frame("round", 12.0)
    with pytest.raises(ReasoningError, match="robot's description"):
        REASONER.judge(JudgeRequest(task="insert", outcome=f.outcome(), checks=[], success_criteria="-",
                                    calibration=f.calibration))
