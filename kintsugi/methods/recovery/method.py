"""The paper's method: every skill checked, failures analysed and recovered (Sec. V).

Per skill: mechanical checks (pose, compression limit, OpenCV Table I or the
goal-image comparison) -> the reasoner's fused verdict. On failure: stage 1
analysis (what / why / how, as motions relative to the current goals), stage 2
plan (skills from the `skills` setting, by default CF2..CF4 as published, with
absolute goals), validated and clamped before anything moves. Ten failed
executions in a row end the trial (timeout).

Beyond the paper (both off by default): when the `skills` setting allows approach,
approach is checked too (the free-hanging peg against its goal image: tilt and
where the hole is) and a plan may re-approach, i.e. lift the peg, approach again
with a corrected roll and y, and come down to contact; with `camera.side_view`
each request also carries the side camera's image and calibration.
"""

from __future__ import annotations

import cv2
import numpy as np

from kintsugi.core.registry import METHODS
from kintsugi.methods.recovery.settings import RecoverySettings
from kintsugi.methods.recovery.skill_log import log_skill, peg_figures
from kintsugi.perception.checks import align_check, compression_check, fit_check, pose_check
from kintsugi.perception.compare import compare_to_goal
from kintsugi.perception.segment import PerceptionConfig, measure
from kintsugi.perception.types import CameraCalibration, CheckResult, Pose
from kintsugi.reasoning import make_reasoner
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.roles import ask
from kintsugi.methods.recovery import roles  # noqa: F401 - registers judge, analyze and plan
from kintsugi.methods.recovery.types import (
    AnalyzeRequest,
    Attempt,
    JudgeReply,
    JudgeRequest,
    PlanRequest,
    SkillOutcome,
)
from kintsugi.methods.recovery.validation import validate_plan
from kintsugi.worlds.peg.context import PegContext
from kintsugi.worlds.peg.description import RobotDescription
from kintsugi.worlds.peg.goals import full_goals
from kintsugi.worlds.peg.robot import PegRobot, to_pose
from kintsugi.worlds.peg.skills import SEQUENCE, SKILLS, SkillResult
from kintsugi.worlds.peg.world import HOME_POSE
from kintsugi.core.log import TrialLog

ALWAYS_CHECKED = ("fit", "align", "insert")
"""The paper checks these; approach is checked as well (until it succeeds) when a plan may re-approach;
contact never (the board's height is fixed)."""


def criteria(skill: str, robot: RobotDescription) -> str:
    """Success criteria per checked skill; the insert criterion states the task's own depth and tilt."""
    if skill == "approach":
        return ("The peg hangs clear above the board as in the goal image: tilted the same way (the grasp holds "
                "it as when the goals were taught), and its tip as far from the hole as there, so contact and fit "
                "start where they were taught.")
    if skill == "fit":
        return ("The peg's tip has dropped into the hole and rests against the hole's edge; "
                "Table I: peg centre at or left of the hole centre and its right edge past it.")
    if skill == "align":
        return (f"The peg stands upright over the hole centre with its tip in the hole: within the tilt tolerance, "
                f"and within {robot.insert_max_tilt_deg:.1f} degrees of vertical, the most the hole lets an "
                f"inserted peg lean.")
    return (f"The peg's tip is at least {robot.insert_depth_mm:g} mm below the board top inside the opening and "
            f"its axis within {robot.insert_max_tilt_deg:.1f} degrees of vertical: it is hidden below the board "
            f"surface as far as in the goal image, upright, and the wrist did not hit its compression limit.")


def to_png(image: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    if not ok:
        raise ValueError("could not encode the camera image as PNG")
    return buf.tobytes()


class Recovery:
    def __init__(self, ctx: PegContext, settings: RecoverySettings = RecoverySettings()) -> None:
        self.ctx = ctx
        self.cfg = ctx.cfg
        self.settings = settings
        self.reasoner = RecordingReasoner(make_reasoner(ctx.reasoner), records=[])
        self.goals = {s: dict(v) for s, v in ctx.goals.items()}  # mm / deg, each skill's own axes
        self.goal_images = ctx.goal_images()
        self.goal_png = {s: to_png(img) for s, img in self.goal_images.items()}
        rec = self.settings
        self.allowed = rec.skills  # what a plan may use, in contact-formation order
        self.check_approach = "approach" in self.allowed
        """Until it first succeeds: is the grasp as taught and the hole where the goals assume? Later
        re-approaches are the plan's own deliberate changes and go unchecked, like contact."""
        self.workspace = {"y": rec.workspace_y_mm, "z": rec.workspace_z_mm}
        self.calibration: CameraCalibration | None = None  # set from the robot when the trial starts
        self.robot: RobotDescription | None = None  # likewise: what the robot knows about itself

    def _full_goal(self, skill: str) -> np.ndarray:
        """Full [y, z, roll] goal: '—' axes take the goals of the preceding contact formations."""
        return full_goals(self.goals, HOME_POSE)[skill]

    def _pose_goals(self) -> dict[str, Pose]:
        return {s: to_pose(self._full_goal(s)) for s in self.allowed}

    def run(self, robot: PegRobot, log: TrialLog) -> bool:
        self.calibration = robot.calibration
        self.robot = robot.description(self.ctx.goals)
        try:
            return self._run(robot, log)
        finally:
            log.transcript.extend(r.model_dump(mode="json") for r in self.reasoner.records)
            log.figures(peg_figures(log))

    def _run(self, robot: PegRobot, log: TrialLog) -> bool:
        rec = self.settings
        queue, history = list(SEQUENCE), []
        failures, executions, recovering = 0, 0, False
        while queue:
            if executions >= rec.max_executions:
                log.event(robot.sim_time, "timeout", f"{executions} skill executions without finishing")
                return False
            skill = queue.pop(0)
            log.status(f"CF{SKILLS[skill].cf} {skill}{' (recovery)' if recovering else ''}")
            result = robot.execute(skill, self._full_goal(skill))
            executions += 1
            if skill not in ALWAYS_CHECKED and not (skill == "approach" and self.check_approach):
                # assumed to succeed (fixed board height), as in the paper
                log_skill(log, result, robot.sim_time, recovery=recovering)
                continue
            outcome = self._outcome(robot, result)
            checks = self._checks(skill, result, outcome)
            verdict = ask(self.reasoner, "judge", JudgeRequest(
                task=self.ctx.task_text, outcome=outcome, checks=checks, success_criteria=criteria(skill, self.robot),
                goal_image_png=self.goal_png[skill], calibration=robot.calibration,
                side_calibration=robot.side_calibration, robot=self.robot))
            log_skill(log, result, robot.sim_time, recovery=recovering, verdict=verdict.success,
                      message=verdict.explanation)
            log.say("         checks: " + "; ".join(f"{c.name}={'ok' if c.passed else c.message}" for c in checks))
            log.say(f"         verdict: {'SUCCESS' if verdict.success else 'FAILURE'} - {verdict.explanation}")
            word = "SUCCESS" if verdict.success else "FAILURE"
            log.status(f"CF{SKILLS[skill].cf} {skill}", f"last verdict: {skill} {word}")
            history.append(Attempt(skill=skill, goal=outcome.goal, terminal=outcome.terminal,
                                   success=verdict.success, explanation=verdict.explanation))
            if verdict.success:
                failures = 0
                self.check_approach = self.check_approach and skill != "approach"
                if skill == "insert":
                    return True
                if not queue:
                    queue = list(SEQUENCE[SEQUENCE.index(skill) + 1:])
                continue
            failures += 1
            if failures >= rec.max_consecutive_failures:
                log.event(robot.sim_time, "timeout", f"{failures} consecutive failed executions")
                return False
            queue = self._recover(robot, log, outcome, checks, verdict, history)
            log.transition(skill, queue[0])
            recovering = True
        return False

    def _outcome(self, robot: PegRobot, r: SkillResult) -> SkillOutcome:
        side = robot.side_image()
        return SkillOutcome(skill=r.skill, goal=to_pose(r.goal), terminal=to_pose(r.terminal),
                            reached_goal=r.reached, timed_out=r.timed_out, compression_limit=r.compression_limit,
                            wrist_force_z_n=round(robot.wrist_force_z(), 3), image_png=to_png(r.image),
                            side_image_png=None if side is None else to_png(side))

    def _checks(self, skill: str, r: SkillResult, outcome: SkillOutcome) -> list[CheckResult]:
        pcfg = self.cfg.perception
        checks = [pose_check(outcome.goal, outcome.terminal, SKILLS[skill].axes, self.cfg.control.pose_tol_mm),
                  compression_check(r.compression_limit, outcome.wrist_force_z_n)]
        if skill == "approach":
            checks.append(approach_check(r.image, self.goal_images["approach"], self.calibration, pcfg))
        elif skill == "fit":
            checks.append(fit_check(measure(r.image, self.calibration, pcfg)))
        elif skill == "align":
            checks.append(align_check(measure(r.image, self.calibration, pcfg), pcfg))
        else:
            checks.append(compare_to_goal(r.image, self.goal_images["insert"], self.calibration, pcfg))
        return checks

    def _recover(self, robot: PegRobot, log: TrialLog, outcome: SkillOutcome, checks: list[CheckResult],
                 verdict: JudgeReply, history: list[Attempt]) -> list[str]:
        rec = self.settings
        skills = {s: list(SKILLS[s].axes) for s in self.allowed}
        analysis = ask(self.reasoner, "analyze", AnalyzeRequest(
            task=self.ctx.task_text, outcome=outcome, checks=checks, verdict=verdict, goals=self._pose_goals(),
            history=history[-6:], calibration=robot.calibration, side_calibration=robot.side_calibration,
            max_step_mm=rec.max_step_mm, skills=skills, goal_image_png=self.goal_png[outcome.skill],
            robot=self.robot))
        log.say(f"         analysis: {analysis.what_happened} Why: {analysis.why} How: {analysis.how_to_recover}")
        request = PlanRequest(task=self.ctx.task_text, analysis=analysis, goals=self._pose_goals(), skills=skills,
                              max_step_mm=rec.max_step_mm, workspace=self.workspace, robot=self.robot)
        plan = validate_plan(ask(self.reasoner, "plan", request), request)
        for step in plan.steps:
            self.goals[step.skill].update(step.goal)
        for note in plan.notes:
            log.event(robot.sim_time, "plan-clamped", note)
        queue = [s.skill for s in plan.steps]
        if queue[-1] != "insert":
            queue += list(SEQUENCE[SEQUENCE.index(queue[-1]) + 1:])
        for i in range(len(queue) - 1, -1, -1):  # a re-approach always comes down to contact again
            if queue[i] == "approach" and (i + 1 == len(queue) or queue[i + 1] != "contact"):
                queue.insert(i + 1, "contact")
        log.say("         plan: " + " -> ".join(
            f"{s.skill}({', '.join(f'{a}={v:.1f}' for a, v in s.goal.items())})" for s in plan.steps))
        return queue


def approach_check(image: np.ndarray, goal_image: np.ndarray, calib: CameraCalibration,
                   cfg: PerceptionConfig) -> CheckResult:
    """The free-hanging peg against the approach goal image: its tilt and its place relative to the hole.

    A tilt unlike the goal image's means the grasp holds the peg at another angle than when the goals
    were taught; a peg elsewhere relative to the hole means the hole is not where the goals assume.
    """
    now, goal = measure(image, calib, cfg), measure(goal_image, calib, cfg)
    if now.peg is None or now.hole is None or goal.peg is None or goal.hole is None:
        return CheckResult(name="vision_approach", passed=False,
                           message="peg or hole not visible in the image or the goal image.")
    d_tilt = now.peg.tilt_deg - goal.peg.tilt_deg
    offset, goal_offset = now.peg.center_mm[0] - now.hole.center_mm[0], goal.peg.center_mm[0] - goal.hole.center_mm[0]
    passed = abs(d_tilt) <= cfg.tilt_tol_deg and abs(offset - goal_offset) <= cfg.align_tol_mm
    return CheckResult(
        name="vision_approach", passed=passed,
        message=(f"peg tilt {now.peg.tilt_deg:+.1f} deg (goal image {goal.peg.tilt_deg:+.1f} deg, difference "
                 f"{d_tilt:+.1f}); peg centre {offset:+.1f} mm from the hole centre along y (goal image "
                 f"{goal_offset:+.1f} mm, difference {offset - goal_offset:+.1f})."),
        measurements={"tilt_deg": now.peg.tilt_deg, "goal_tilt_deg": goal.peg.tilt_deg, "tilt_difference_deg": d_tilt,
                      "offset_y_mm": offset, "goal_offset_y_mm": goal_offset,
                      "offset_difference_mm": offset - goal_offset})


@METHODS.register("recovery", "checks every skill and recovers failures with a reasoner (the paper's method)",
                  tags=("peg-insertion", "reasoner"), config=RecoverySettings)
def make_recovery(ctx: PegContext, settings: RecoverySettings) -> Recovery:
    return Recovery(ctx, settings)
