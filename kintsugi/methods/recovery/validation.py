"""Last line of defence between a reasoner's plan and the robot.

Structural problems (skills the request does not allow, i.e. outside
the method's `skills` setting, axes a skill does not own, non-finite numbers) are rejected
with `PlanInvalid`, so a backend can ask the model to repair its reply. Numeric
overreach is never rejected but clamped: each goal may move at most
`max_step_mm` (degrees for roll) from the skill's current goal (the paper's one
real-robot failure was an over-large update) and must stay in the workspace.
Every clamp is written down in `ValidatedPlan.notes`.
"""

from __future__ import annotations

import json
import math
from typing import Any, get_args

from annotated_types import MaxLen
from pydantic import ValidationError

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning.jsontext import describe_validation_error
from kintsugi.methods.recovery.types import AnalyzeReply, AnalyzeRequest, PlanReply, PlanRequest, RecoverySkill
from kintsugi.perception.types import Axis, Pose


def _max_plan_steps() -> int:
    for meta in PlanReply.model_fields["steps"].metadata:
        if isinstance(meta, MaxLen):
            return meta.max_length
    raise RuntimeError("PlanReply.steps has no max_length; validation needs one")


SKILL_NAMES: tuple[str, ...] = get_args(RecoverySkill)
MAX_PLAN_STEPS = _max_plan_steps()
"""Same limit as the PlanReply schema, so validation and parsing agree."""


class PlanInvalid(ReasoningError):
    """A plan (or analysis) is structurally unusable; the message says what to change."""


class ValidatedStep(StrictModel):
    """One executable step: every axis the skill owns, clamped; `pose` is the full goal pose."""

    skill: str
    goal: dict[Axis, float]
    pose: Pose


class ValidatedPlan(StrictModel):
    steps: list[ValidatedStep]
    notes: list[str] = []


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _check_request(request: PlanRequest) -> None:
    step = request.max_step_mm
    if not (math.isfinite(step) and step >= 0):
        raise PlanInvalid(f"plan request has max_step_mm={step!r}; the caller must pass a finite limit >= 0")


def validate_plan(reply: PlanReply, request: PlanRequest) -> ValidatedPlan:
    """Reject unusable plans, clamp usable ones; never returns a goal outside the limits.

    A step that omits one of its skill's axes keeps the current goal for it. An
    axis's limit is `max_step_mm` around the current goal intersected with the
    workspace bounds; if that intersection is empty the request itself is
    inconsistent and the plan is rejected rather than moved outside either.
    """
    _check_request(request)
    steps_in = list(reply.steps)
    notes: list[str] = []
    if not steps_in:
        raise PlanInvalid("the plan has no steps; give at least one of the recovery skills, ending with insert")
    if len(steps_in) > MAX_PLAN_STEPS:
        notes.append(f"plan had {len(steps_in)} steps; kept the first {MAX_PLAN_STEPS}")
        steps_in = steps_in[:MAX_PLAN_STEPS]

    known = ", ".join(f"{s} {list(a)}" for s, a in request.skills.items()) or "(none)"
    steps_out: list[ValidatedStep] = []
    for i, step in enumerate(steps_in):
        where = f"step {i + 1} ({step.skill})"
        if step.skill not in request.skills:
            what = "is not allowed in this robot's recovery plans" if step.skill in SKILL_NAMES else "is unknown"
            raise PlanInvalid(f"{where}: skill {step.skill!r} {what}; use only these skills and axes: {known}")
        owned = request.skills[step.skill]
        current = request.goals.get(step.skill)
        if current is None:
            raise PlanInvalid(
                f"{where}: no current goal for skill {step.skill!r} in the request; "
                f"the caller must pass goals for every skill in `skills`"
            )
        goal: dict[Axis, float] = {}
        for axis, value in step.goal.items():
            if axis not in owned:
                raise PlanInvalid(
                    f"{where}: skill {step.skill!r} does not control axis {axis!r}; it owns only {list(owned)}"
                )
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise PlanInvalid(f"{where}: goal {axis}={value!r} is not a finite number (mm or degrees)")
        for axis in owned:
            now = float(getattr(current, axis))
            if not math.isfinite(now):
                raise PlanInvalid(f"{where}: current goal {axis}={now!r} is not finite; the caller's goals are corrupt")
            wanted = float(step.goal.get(axis, now)) + 0.0  # + 0.0 turns -0.0 into 0.0
            lo, hi = now - request.max_step_mm, now + request.max_step_mm
            bounds = request.workspace.get(axis)
            if bounds is not None:
                lo, hi = max(lo, bounds[0]), min(hi, bounds[1])
                if lo > hi:
                    raise PlanInvalid(
                        f"{where}: current goal {axis}={_fmt(now)} is more than max_step_mm={_fmt(request.max_step_mm)} "
                        f"outside the workspace [{_fmt(bounds[0])}, {_fmt(bounds[1])}]; the caller's goals "
                        f"or workspace are inconsistent"
                    )
            value = min(max(wanted, lo), hi) + 0.0  # a bound taken from a -0.0 goal stays non-negative zero
            if value != wanted:
                reason = _clamp_reason(wanted, value, now, request.max_step_mm, bounds)
                notes.append(f"{where}: {axis} {_fmt(wanted)} -> {_fmt(value)} ({reason})")
            goal[axis] = value
        pose = current.model_copy(update=dict(goal))
        steps_out.append(ValidatedStep(skill=step.skill, goal=goal, pose=pose))
    if steps_out[-1].skill != "insert" and "insert" in request.skills:
        notes.append("plan does not end with insert; the task is not complete until the peg is inserted")
    return ValidatedPlan(steps=steps_out, notes=notes)


def _clamp_reason(wanted: float, value: float, now: float, max_step: float,
                  bounds: tuple[float, float] | None) -> str:
    if bounds is not None and (value == bounds[0] or value == bounds[1]) and abs(value - now) < max_step:
        return f"outside workspace [{_fmt(bounds[0])}, {_fmt(bounds[1])}]"
    return f"change {_fmt(wanted - now)} from current goal {_fmt(now)} exceeds max step {_fmt(max_step)}"


def parse_plan(raw: Any, request: PlanRequest) -> ValidatedPlan:
    """Parse an untrusted reply (JSON text or decoded object) into a validated plan.

    Every failure is a `PlanInvalid` (a ReasoningError); nothing else escapes.
    """
    if isinstance(raw, (str, bytes, bytearray)):
        try:
            raw = json.loads(raw)
        except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
            raise PlanInvalid(f"plan reply is not valid JSON ({exc}); reply with one JSON object") from None
    try:
        reply = PlanReply.model_validate(raw)
    except ValidationError as exc:
        raise PlanInvalid(f"plan reply does not match the schema: {describe_validation_error(exc)}") from None
    return validate_plan(reply, request)


def validate_analysis(reply: AnalyzeReply, request: AnalyzeRequest) -> AnalyzeReply:
    """Reject analyses whose motions cannot be turned into a plan.

    Motions must name a skill that has a current goal, an axis that skill owns
    (when the request lists skills), and a finite delta. Large deltas are allowed
    here; the plan stage clamps them.
    """
    skills = request.skills
    for i, motion in enumerate(reply.motions):
        where = f"motion {i + 1} ({motion.skill} {motion.axis})"
        if request.goals and motion.skill not in request.goals:
            raise PlanInvalid(f"{where}: skill {motion.skill!r} has no current goal; use one of {sorted(request.goals)}")
        if motion.skill in skills and motion.axis not in skills[motion.skill]:
            raise PlanInvalid(
                f"{where}: skill {motion.skill!r} does not control axis {motion.axis!r}; it owns only {skills[motion.skill]}"
            )
        if not math.isfinite(motion.delta):
            raise PlanInvalid(f"{where}: delta {motion.delta!r} is not a finite number")
    if request.goals and reply.restart_from not in request.goals:
        raise PlanInvalid(f"restart_from {reply.restart_from!r} has no current goal; use one of {sorted(request.goals)}")
    return reply
