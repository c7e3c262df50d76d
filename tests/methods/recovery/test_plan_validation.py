"""validate_plan / parse_plan: hostile replies never escape as anything but ReasoningError,
and every accepted plan obeys the step and workspace limits."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.recovery.types import (
    AnalyzeReply,
    AnalyzeRequest,
    JudgeReply,
    PlanReply,
    PlanRequest,
    PlanStep,
    SkillOutcome,
)
from kintsugi.perception.types import CameraCalibration, Pose
from kintsugi.methods.recovery.validation import (
    MAX_PLAN_STEPS,
    PlanInvalid,
    ValidatedPlan,
    parse_plan,
    validate_analysis,
    validate_plan,
)

SKILLS = {"fit": ["y"], "align": ["y"], "insert": ["z"]}
ANALYSIS = AnalyzeReply(what_happened="-", why="-", how_to_recover="-", restart_from="align")


def request(goals: dict[str, Pose] | None = None, max_step: float = 5.0,
            workspace: dict | None = None) -> PlanRequest:
    return PlanRequest(
        task="peg", analysis=ANALYSIS, skills=SKILLS, max_step_mm=max_step,
        goals=goals or {"fit": Pose(y=10.0, z=5.0), "align": Pose(y=12.0, z=5.0), "insert": Pose(y=12.0, z=-20.0)},
        workspace={"y": (-40.0, 40.0), "z": (-40.0, 30.0)} if workspace is None else workspace,
    )


def plan(*steps: tuple[str, dict]) -> PlanReply:
    return PlanReply(steps=[PlanStep(skill=s, goal=g) for s, g in steps])


# --- hostile input strategies --------------------------------------------------

hostile_numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e308, -1e308, -0.0, 0.0, 5e-324, float("nan"), float("inf"), float("-inf")]),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.sampled_from(["5", "-3.5", "nan", "inf", "-inf", "1e999", "0x10", "", " 7 ", "twelve", "1_000"]),
    st.booleans(),
    st.none(),
)
junk = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4),
    max_leaves=12,
)
skill_names = st.sampled_from(["fit", "align", "insert", "approach", "contact", "grasp", "FIT", "", "insert "]) | st.text(max_size=8)
axis_names = st.sampled_from(["y", "z", "roll", "x", "Y", ""]) | st.text(max_size=4)
goals = st.dictionaries(axis_names, hostile_numbers | junk, max_size=4) | junk
step = st.one_of(
    st.fixed_dictionaries({"skill": skill_names, "goal": goals}),
    st.fixed_dictionaries({"skill": skill_names, "goal": goals}, optional={"why": junk, "extra": junk}),
    st.fixed_dictionaries({"skill": skill_names}),
    junk,
)
# plausible steps: known skills and owned axes, hostile values — reaches the clamping code often
plausible_step = st.one_of(
    st.builds(lambda v: {"skill": "fit", "goal": {"y": v}}, hostile_numbers),
    st.builds(lambda v: {"skill": "align", "goal": {"y": v}}, hostile_numbers),
    st.builds(lambda v: {"skill": "insert", "goal": {"z": v}}, hostile_numbers),
    st.just({"skill": "insert", "goal": {}}),
)
steps = st.one_of(
    st.lists(plausible_step, min_size=1, max_size=MAX_PLAN_STEPS),
    st.lists(step | plausible_step, max_size=10),
    st.lists(plausible_step, min_size=MAX_PLAN_STEPS + 1, max_size=200),  # huge lists
    junk,
)
raw_replies = st.one_of(
    st.fixed_dictionaries({"steps": steps}),
    st.fixed_dictionaries({"steps": steps}, optional={"notes": junk, "steps_extra": junk}),
    junk,
)


def _as_wire(raw: object, mode: int) -> object:
    """Feed the same reply as a decoded object, as JSON text, or as truncated JSON text."""
    if mode == 0:
        return raw
    try:
        text = json.dumps(raw, allow_nan=True)
    except (TypeError, ValueError):  # e.g. integers too large for some encoders
        return raw
    return text if mode == 1 else text[: max(0, len(text) // 2)]


finite = st.floats(min_value=-30.0, max_value=30.0, allow_nan=False)


@st.composite
def requests(draw: st.DrawFn) -> PlanRequest:
    """Random but consistent requests: every current goal lies inside the workspace."""
    g = {s: Pose(y=draw(finite), z=draw(finite)) for s in SKILLS}
    workspace = {}
    for axis in ("y", "z"):
        if draw(st.booleans()):
            values = [getattr(p, axis) for p in g.values()]
            workspace[axis] = (min(values) - draw(st.floats(0, 10)), max(values) + draw(st.floats(0, 10)))
    return request(g, max_step=draw(st.floats(0.0, 20.0)), workspace=workspace)


def assert_within_limits(result: ValidatedPlan, req: PlanRequest) -> None:
    """Everything the robot may be sent: known skill/axis pairs, finite, within step and workspace."""
    assert 1 <= len(result.steps) <= MAX_PLAN_STEPS
    for s in result.steps:
        assert s.skill in req.skills
        assert set(s.goal) == set(req.skills[s.skill])
        current = req.goals[s.skill]
        for axis, value in s.goal.items():
            now = getattr(current, axis)
            assert math.isfinite(value)
            assert not (value == 0.0 and math.copysign(1.0, value) < 0)  # no -0.0 reaches the robot
            assert abs(value - now) <= req.max_step_mm + 1e-9 * max(1.0, abs(now))
            if axis in req.workspace:
                lo, hi = req.workspace[axis]
                assert lo <= value <= hi
            assert getattr(s.pose, axis) == value
        untouched = {"y", "z", "roll"} - set(s.goal)
        assert all(getattr(s.pose, a) == getattr(current, a) for a in untouched)


@pytest.mark.slow
@settings(max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(raw=raw_replies, mode=st.integers(0, 2), req=requests())
def test_hostile_replies_are_rejected_or_safe(raw: object, mode: int, req: PlanRequest) -> None:
    try:
        result = parse_plan(_as_wire(raw, mode), req)
    except ReasoningError as exc:
        assert str(exc)  # every rejection says something
        event("rejected")
        return
    event("accepted, clamped" if any("->" in n for n in result.notes) else "accepted")
    assert_within_limits(result, req)


numeric_values = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.floats(-60.0, 60.0),
    st.sampled_from([1e308, -1e308, -0.0, 5e-324, "-0.0", "1e300", "12.5", True, False]),
    st.integers(-(10**6), 10**6),
)
numeric_step = st.sampled_from(["fit", "align", "insert"]).flatmap(
    lambda skill: st.builds(lambda goal: {"skill": skill, "goal": goal},
                            st.dictionaries(st.just(SKILLS[skill][0]), numeric_values, max_size=1))
)


@pytest.mark.slow
@settings(max_examples=1000, deadline=None)
@given(raw=st.lists(numeric_step, min_size=1, max_size=MAX_PLAN_STEPS), as_text=st.booleans(), req=requests())
def test_numeric_replies_are_always_clamped_into_limits(raw: list, as_text: bool, req: PlanRequest) -> None:
    """Well-formed plans with extreme numbers: always accepted, always inside the limits."""
    reply = {"steps": raw}
    result = parse_plan(json.dumps(reply) if as_text else reply, req)
    assert_within_limits(result, req)


@settings(max_examples=300, deadline=None)
@given(req=requests(), offsets=st.lists(st.floats(-1.0, 1.0), min_size=1, max_size=MAX_PLAN_STEPS))
def test_values_within_limits_pass_unchanged(req: PlanRequest, offsets: list[float]) -> None:
    order = ["fit", "align", "insert"]
    wanted = []
    for i, f in enumerate(offsets):
        skill = order[i % 3]
        axis = SKILLS[skill][0]
        now = getattr(req.goals[skill], axis)
        value = now + f * req.max_step_mm
        lo, hi = req.workspace.get(axis, (-math.inf, math.inf))
        if not lo <= value <= hi:
            value = now
        wanted.append((skill, {axis: value}))
    result = validate_plan(plan(*wanted), req)
    assert [(s.skill, s.goal) for s in result.steps] == wanted
    assert not [n for n in result.notes if "->" in n]


# --- golden clamping cases ------------------------------------------------------

def test_step_limit_clamps_both_directions_with_notes() -> None:
    result = validate_plan(plan(("fit", {"y": 100.0}), ("align", {"y": -100.0}), ("insert", {"z": -21.0})), request())
    assert [s.goal for s in result.steps] == [{"y": 15.0}, {"y": 7.0}, {"z": -21.0}]
    assert result.notes == [
        "step 1 (fit): y 100 -> 15 (change 90 from current goal 10 exceeds max step 5)",
        "step 2 (align): y -100 -> 7 (change -112 from current goal 12 exceeds max step 5)",
    ]


def test_workspace_clamps_inside_step_limit() -> None:
    result = validate_plan(plan(("align", {"y": 16.0}), ("insert", {"z": -20.0})),
                           request(workspace={"y": (-14.0, 14.0)}))
    assert result.steps[0].goal == {"y": 14.0}
    assert result.notes == ["step 1 (align): y 16 -> 14 (outside workspace [-14, 14])"]


def test_missing_axis_keeps_current_goal_and_pose_is_complete() -> None:
    result = validate_plan(plan(("align", {}), ("insert", {})), request())
    assert [s.goal for s in result.steps] == [{"y": 12.0}, {"z": -20.0}]
    assert result.steps[1].pose == Pose(y=12.0, z=-20.0) and result.notes == []


def test_negative_zero_becomes_zero() -> None:
    result = validate_plan(plan(("insert", {"z": -0.0})), request(goals={
        "fit": Pose(y=0, z=0), "align": Pose(y=0, z=0), "insert": Pose(y=0, z=0)}))
    assert math.copysign(1.0, result.steps[0].goal["z"]) == 1.0


def test_zero_step_limit_freezes_goals() -> None:
    result = validate_plan(plan(("align", {"y": 13.0}), ("insert", {"z": -20.0})), request(max_step=0.0))
    assert result.steps[0].goal == {"y": 12.0} and len(result.notes) == 1


def test_over_long_plan_is_truncated_with_note() -> None:
    long = PlanReply.model_construct(steps=[PlanStep(skill="insert", goal={"z": -20.0})] * (MAX_PLAN_STEPS + 3))
    result = validate_plan(long, request())
    assert len(result.steps) == MAX_PLAN_STEPS
    assert f"kept the first {MAX_PLAN_STEPS}" in result.notes[0]


def test_plan_not_ending_with_insert_is_noted() -> None:
    result = validate_plan(plan(("align", {"y": 12.0})), request())
    assert "does not end with insert" in result.notes[-1]


@pytest.mark.parametrize(
    ("reply", "message"),
    [
        (PlanReply.model_construct(steps=[]), "no steps"),
        (plan(("insert", {"y": 3.0})), "does not control axis 'y'"),
        (plan(("align", {"y": float("nan")})), "not a finite number"),
        (plan(("align", {"y": float("inf")})), "not a finite number"),
        (PlanReply.model_construct(steps=[PlanStep.model_construct(skill="grasp", goal={})]), "skill 'grasp' is unknown"),
    ],
)
def test_structural_problems_are_rejected(reply: PlanReply, message: str) -> None:
    with pytest.raises(PlanInvalid, match=message):
        validate_plan(reply, request())


def test_skill_missing_from_request_is_rejected() -> None:
    req = request().model_copy(update={"skills": {"fit": ["y"], "insert": ["z"]}})
    with pytest.raises(PlanInvalid, match="skill 'align' is not allowed.*fit \\['y'\\], insert \\['z'\\]"):
        validate_plan(plan(("align", {"y": 12.0})), req)
    no_goal = request().model_copy(update={"goals": {"fit": Pose(y=0, z=0), "align": Pose(y=0, z=0)}})
    with pytest.raises(PlanInvalid, match="no current goal for skill 'insert'"):
        validate_plan(plan(("insert", {"z": 0.0})), no_goal)


def test_inconsistent_request_is_rejected_not_moved() -> None:
    req = request(workspace={"y": (30.0, 40.0)})  # align goal 12 is > 5 mm outside
    with pytest.raises(PlanInvalid, match="outside the workspace"):
        validate_plan(plan(("align", {"y": 12.0})), req)
    with pytest.raises(PlanInvalid, match="max_step_mm"):
        validate_plan(plan(("align", {"y": 12.0})), request(max_step=float("nan")))


def test_parse_plan_wraps_json_and_schema_errors() -> None:
    with pytest.raises(PlanInvalid, match="not valid JSON"):
        parse_plan('{"steps": [', request())
    with pytest.raises(PlanInvalid, match="does not match the schema"):
        parse_plan({"steps": [{"skill": "align", "goal": {"y": "twelve"}}]}, request())
    with pytest.raises(PlanInvalid, match="does not match the schema"):
        parse_plan({"steps": [], "extra": 1}, request())
    ok = parse_plan('{"steps": [{"skill": "insert", "goal": {"z": "-19.5"}}]}', request())
    assert ok.steps[0].goal == {"z": -19.5}


def analyze_request() -> AnalyzeRequest:
    png = b"\x89PNG\r\n\x1a\n"
    outcome = SkillOutcome(skill="align", goal=Pose(y=12, z=5), terminal=Pose(y=11, z=5), reached_goal=True,
                           timed_out=False, compression_limit=False, image_png=png)
    cal = CameraCalibration(width=4, height=4, px_per_mm=1, cu=2, cv=2, y0_mm=0, z0_mm=0)
    return AnalyzeRequest(task="peg", outcome=outcome, checks=[], verdict=JudgeReply(success=False, explanation="-"),
                          goals=request().goals, history=[], calibration=cal, max_step_mm=5, skills=SKILLS)


@pytest.mark.parametrize(
    ("motion", "message"),
    [
        ({"skill": "insert", "axis": "y", "delta": 1.0}, "does not control axis 'y'"),
        ({"skill": "align", "axis": "y", "delta": float("nan")}, "not a finite number"),
    ],
)
def test_validate_analysis_rejects_unusable_motions(motion: dict, message: str) -> None:
    reply = AnalyzeReply.model_validate(ANALYSIS.model_dump() | {"motions": [motion]})
    with pytest.raises(PlanInvalid, match=message):
        validate_analysis(reply, analyze_request())


def test_validate_analysis_allows_large_deltas_and_unknown_goal_skills_fail() -> None:
    big = AnalyzeReply.model_validate(ANALYSIS.model_dump() | {"motions": [{"skill": "align", "axis": "y", "delta": 40}]})
    assert validate_analysis(big, analyze_request()) is big
    req = analyze_request().model_copy(update={"goals": {"insert": Pose(y=0, z=0)}})
    with pytest.raises(PlanInvalid, match="has no current goal"):
        validate_analysis(big, req)
