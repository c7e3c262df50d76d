"""The paper's method: every skill checked, failures analysed and recovered (Sec. V).

Per skill: mechanical checks (pose, compression limit, OpenCV Table I or the
goal-image comparison) -> the reasoner's fused verdict. On failure: stage 1
analysis (what / why / how, as motions relative to the current goals), stage 2
plan (skills from CF2..CF4 with absolute goals), validated and clamped before
anything moves. Ten failed executions in a row end the trial (timeout).
"""

from __future__ import annotations

import cv2
import numpy as np

from kintsugi.methods import METHODS
from kintsugi.methods.skill_log import log_skill
from kintsugi.perception.checks import align_check, compression_check, fit_check, pose_check
from kintsugi.perception.compare import compare_to_goal
from kintsugi.perception.segment import measure
from kintsugi.reasoning import make_reasoner
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.types import (
    AnalyzeRequest,
    Attempt,
    CheckResult,
    CameraCalibration,
    JudgeReply,
    JudgeRequest,
    PlanRequest,
    Pose,
    RobotDescription,
    SkillOutcome,
)
from kintsugi.reasoning.validation import validate_plan
from kintsugi.tasks.peg.context import PegContext
from kintsugi.tasks.peg.goals import full_goals
from kintsugi.tasks.peg.robot import PegRobot, to_pose
from kintsugi.tasks.peg.skills import SKILLS, SkillResult
from kintsugi.tasks.peg.world import HOME_POSE
from kintsugi.trial import TrialLog

RECOVERABLE = ("fit", "align", "insert")
CRITERIA = {
    "fit": "The peg's tip has dropped into the hole and rests against the hole's edge; "
           "Table I: peg centre at or left of the hole centre and its right edge past it.",
    "align": "The peg stands upright (within the tilt tolerance) over the hole centre with its tip in the hole.",
    "insert": "The peg is at least 10 mm deep in the hole: it is hidden below the board surface as far as in "
              "the goal image, and the wrist did not hit its compression limit.",
}


def to_png(image: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    if not ok:
        raise ValueError("could not encode the camera image as PNG")
    return buf.tobytes()


class Recovery:
    def __init__(self, ctx: PegContext) -> None:
        self.ctx = ctx
        self.cfg = ctx.cfg
        self.reasoner = RecordingReasoner(make_reasoner(ctx.reasoner), records=[])
        self.goals = {s: dict(v) for s, v in ctx.goals.items()}  # mm / deg, each skill's own axes
        self.goal_images = ctx.goal_images()
        self.goal_png = {s: to_png(img) for s, img in self.goal_images.items()}
        rec = self.cfg.recovery
        self.workspace = {"y": rec.workspace_y_mm, "z": rec.workspace_z_mm}
        self.calibration: CameraCalibration | None = None  # set from the robot when the trial starts
        self.robot: RobotDescription | None = None  # likewise: what the robot knows about itself

    def _full_goal(self, skill: str) -> np.ndarray:
        """Full [y, z, roll] goal: '—' axes take the goals of the preceding contact formations."""
        return full_goals(self.goals, HOME_POSE)[skill]

    def _pose_goals(self) -> dict[str, Pose]:
        return {s: to_pose(self._full_goal(s)) for s in RECOVERABLE}

    def run(self, robot: PegRobot, log: TrialLog) -> bool:
        self.calibration = robot.calibration
        self.robot = robot.description(self.ctx.goals)
        try:
            return self._run(robot, log)
        finally:
            log.transcript.extend(r.model_dump(mode="json") for r in self.reasoner.records)

    def _run(self, robot: PegRobot, log: TrialLog) -> bool:
        rec = self.cfg.recovery
        for skill in ("approach", "contact"):  # assumed to succeed (fixed board height), as in the paper
            log.status(f"CF{SKILLS[skill].cf} {skill}")
            log_skill(log, robot.execute(skill, self._full_goal(skill)), robot.sim_time)
        queue, history = list(RECOVERABLE), []
        failures, executions, recovering = 0, 2, False
        while queue:
            if executions >= rec.max_executions:
                log.event(robot.sim_time, "timeout", f"{executions} skill executions without finishing")
                return False
            skill = queue.pop(0)
            log.status(f"CF{SKILLS[skill].cf} {skill}{' (recovery)' if recovering else ''}")
            result = robot.execute(skill, self._full_goal(skill))
            executions += 1
            outcome = self._outcome(robot, result)
            checks = self._checks(skill, result, outcome)
            verdict = self.reasoner.judge(JudgeRequest(
                task=self.ctx.task_text, outcome=outcome, checks=checks, success_criteria=CRITERIA[skill],
                goal_image_png=self.goal_png[skill], calibration=robot.calibration, robot=self.robot))
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
                if skill == "insert":
                    return True
                if not queue:
                    queue = list(RECOVERABLE[RECOVERABLE.index(skill) + 1:])
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
        return SkillOutcome(skill=r.skill, goal=to_pose(r.goal), terminal=to_pose(r.terminal),
                            reached_goal=r.reached, timed_out=r.timed_out, compression_limit=r.compression_limit,
                            wrist_force_z_n=round(robot.wrist_force_z(), 3), image_png=to_png(r.image))

    def _checks(self, skill: str, r: SkillResult, outcome: SkillOutcome) -> list[CheckResult]:
        pcfg = self.cfg.perception
        checks = [pose_check(outcome.goal, outcome.terminal, SKILLS[skill].axes, self.cfg.control.pose_tol_mm),
                  compression_check(r.compression_limit, outcome.wrist_force_z_n)]
        if skill == "fit":
            checks.append(fit_check(measure(r.image, self.calibration, pcfg)))
        elif skill == "align":
            checks.append(align_check(measure(r.image, self.calibration, pcfg), pcfg))
        else:
            checks.append(compare_to_goal(r.image, self.goal_images["insert"], self.calibration, pcfg))
        return checks

    def _recover(self, robot: PegRobot, log: TrialLog, outcome: SkillOutcome, checks: list[CheckResult],
                 verdict: JudgeReply, history: list[Attempt]) -> list[str]:
        rec = self.cfg.recovery
        skills = {s: list(SKILLS[s].axes) for s in RECOVERABLE}
        analysis = self.reasoner.analyze(AnalyzeRequest(
            task=self.ctx.task_text, outcome=outcome, checks=checks, verdict=verdict, goals=self._pose_goals(),
            history=history[-6:], calibration=robot.calibration, max_step_mm=rec.max_step_mm, skills=skills,
            goal_image_png=self.goal_png[outcome.skill], robot=self.robot))
        log.say(f"         analysis: {analysis.what_happened} Why: {analysis.why} How: {analysis.how_to_recover}")
        request = PlanRequest(task=self.ctx.task_text, analysis=analysis, goals=self._pose_goals(), skills=skills,
                              max_step_mm=rec.max_step_mm, workspace=self.workspace, robot=self.robot)
        plan = validate_plan(self.reasoner.plan(request), request)
        for step in plan.steps:
            self.goals[step.skill].update(step.goal)
        for note in plan.notes:
            log.event(robot.sim_time, "plan-clamped", note)
        queue = [s.skill for s in plan.steps]
        if queue[-1] != "insert":
            queue += list(RECOVERABLE[RECOVERABLE.index(queue[-1]) + 1:])
        log.say("         plan: " + " -> ".join(
            f"{s.skill}({', '.join(f'{a}={v:.1f}' for a, v in s.goal.items())})" for s in plan.steps))
        return queue


@METHODS.register("recovery", "checks every skill and recovers failures with a reasoner (the paper's method)",
                  tags=("peg-insertion", "reasoner"))
def make_recovery(ctx: PegContext) -> Recovery:
    return Recovery(ctx)
