"""The peg recovery's roles (judge, analyze, plan), registered for every backend.

Each role names its request and reply types, its prompt (`prompts/<role>.md` beside this module,
with `prompts/system.md` as the system prompt), the robot section every prompt carries, its check
and its embedded answer (`embedded.judge`, `diagnosis.analyze`, `diagnosis.plan`). The plan's
check rejects structural problems only (unknown skills, unowned axes: a model is asked to repair
them); clamping stays the caller's (`validation.validate_plan`), so the transcript keeps the plan
as the reasoner gave it.
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.recovery import embedded
from kintsugi.methods.recovery.prompting import robot_section
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    JudgeReply,
    JudgeRequest,
    PlanReply,
    PlanRequest,
)
from kintsugi.methods.recovery.validation import validate_analysis, validate_plan
from kintsugi.reasoning.roles import ROLES, Role, ToolRoute

PACKAGE = "kintsugi.methods.recovery"
IMAGE_LABELS = {
    "outcome.image_png": "terminal camera image at the end of the skill",
    "goal_image_png": "goal image: this skill's terminal image in the default condition (what success looks like)",
}
"""What the images of a judge or analyze request show, told to a model with each image."""
PLAN_TEXT_HINT = ('Write each function call as one step {"skill": <function name>, "goal": {<its arguments>}}, '
                  'in execution order, inside {"steps": [...]}.')


def plan_tools(request: PlanRequest) -> ToolRoute:
    """One function per recovery skill; its parameters are the skill's axes as absolute goals."""
    tools = []
    for skill, axes in request.skills.items():
        current = request.goals.get(skill)
        props = {}
        for axis in axes:
            unit = "degrees" if axis == "roll" else "mm"
            now = f"; current goal {getattr(current, axis):g}" if current is not None else ""
            props[axis] = {"type": "number", "description": f"absolute goal {axis} in {unit}{now}"}
        tools.append(
            {
                "type": "function",
                "function": {
                    "name": skill,
                    "description": f"Execute the {skill} skill with an absolute goal for {', '.join(axes)}. "
                    f"Each value may differ from the current goal by at most {request.max_step_mm:g}.",
                    "parameters": {
                        "type": "object",
                        "properties": props,
                        "required": list(axes),
                        "additionalProperties": False,
                    },
                    "strict": True,
                },
            }
        )
    return ToolRoute(tools=tools, text_hint=PLAN_TEXT_HINT,
                     to_data=lambda calls: {"steps": [{"skill": name, "goal": args} for name, args in calls]})


def check_plan(reply: PlanReply, request: PlanRequest) -> PlanReply:
    """Structural errors go back to the model; the reply itself is kept unclamped."""
    validate_plan(reply, request)
    return reply


def _role(name: str, request: Any, reply: Any, solver: Any, **kw: Any) -> Role:
    return ROLES.register(Role(name=name, request=request, reply=reply, package=PACKAGE, embedded=solver,
                               sections=robot_section, image_labels=IMAGE_LABELS, **kw))


JUDGE = _role("judge", JudgeRequest, JudgeReply, embedded.judge)
ANALYZE = _role("analyze", AnalyzeRequest, AnalyzeReply, embedded.analyze, check=validate_analysis)
PLAN = _role("plan", PlanRequest, PlanReply, embedded.plan, check=check_plan, tools=plan_tools)

__all__ = ["ANALYZE", "JUDGE", "PLAN", "check_plan", "plan_tools"]
