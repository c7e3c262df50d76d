"""Hostile and malformed formulation and adaptation replies (>= 1,000): each one is a clear BadReply or a
reply whose numbers are clamped into bounds, never a crash. Cost code that passes the language runs in the
sandbox probe (child process, CPU/memory/wall limits); code that would never finish cannot be written in it."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.coral.adapt import check_adaptation, parse_adaptation
from kintsugi.methods.coral.types import AdaptRequest, AttemptHistory
from kintsugi.methods.coral.costlib import compose
from kintsugi.methods.coral.formulate import MAX_RADIUS_M, MAX_TIMEOUT_S, check_formulation, parse_formulation
from kintsugi.methods.coral.priors import FRICTION_BOUNDS
from tests.coral_scenes import PUSH

K, T = 16, 5
GOOD = compose(PUSH)
GOOD_JSON = json.loads(GOOD.model_dump_json())

HOSTILE_CODE = [
    "import os\ndef push_cost(tcp): return 0",
    "def push_cost(tcp):\n    return tcp.__class__.__subclasses__()",
    "def push_cost(tcp):\n    return open('/etc/passwd')",
    "def push_cost(tcp):\n    while True:\n        pass\n    return tcp",
    "def push_cost(tcp):\n    return [x for x in range(10 ** 9)]",
    "def push_cost(tcp):\n    return tcp ** 99999",
    "def push_cost(tcp):\n    return push_cost(tcp)",
    "def push_cost(tcp):\n    return eval('1')",
    "def push_cost(tcp):\n    return sqrt(-1.0 - tcp[..., 0] ** 2)",
    "def push_cost(tcp):\n    return tcp",
    "def push_cost(secret_truth):\n    return secret_truth",
    "def push_cost(tcp):\n    return " + "(" * 200 + "1" + ")" * 200,
    "def push_cost(tcp):\n    x = 1\n" + "    x = x + 1\n" * 3000 + "    return x",
    "lambda: 0",
    "def push_cost(tcp):\n    return log(0.0 * tcp[..., 0])",
    "",
    "\x00",
]
NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**12, 10**12),
                   st.sampled_from([-1.0, 0.0, 1e9, -1e9, float("nan"), float("inf")]))
VALUE = st.recursive(st.one_of(st.none(), st.booleans(), NUMBER, st.text(max_size=20)),
                     lambda c: st.one_of(st.lists(c, max_size=3), st.dictionaries(st.text(max_size=8), c, max_size=3)),
                     max_leaves=8)


def _mutate_formulation(data: st.DataObject) -> object:
    reply = json.loads(json.dumps(GOOD_JSON))
    what = data.draw(st.sampled_from(["code", "stage", "region", "key", "drop", "whole", "number"]))
    if what == "code":
        reply["source"] = data.draw(st.one_of(st.sampled_from(HOSTILE_CODE), st.text(max_size=80)))
    elif what == "stage":
        i = data.draw(st.integers(0, len(reply["stages"]) - 1))
        key = data.draw(st.sampled_from(["cost", "done", "grip", "region", "timeout_s", "hold_s", "press_n",
                                         "noise_scale", "keep", "name", "press_axis"]))
        reply["stages"][i][key] = data.draw(st.one_of(VALUE, NUMBER, st.sampled_from(["nope", "open", "__import__"])))
    elif what == "region":
        r = reply["regions"][0]
        key = data.draw(st.sampled_from(["center", "normal", "radius", "object", "standoff", "drop"]))
        r[key] = data.draw(st.one_of(VALUE, st.tuples(NUMBER, NUMBER, NUMBER), NUMBER,
                                     st.sampled_from([[10.0, 0, 0], [0, 0, 0], "wall", "table"])))
    elif what == "key":
        reply[data.draw(st.text(min_size=1, max_size=8))] = data.draw(VALUE)
    elif what == "drop":
        reply.pop(data.draw(st.sampled_from(sorted(reply))))
    elif what == "number":
        reply["stages"][0]["timeout_s"] = data.draw(NUMBER)
        reply["regions"][0]["radius"] = data.draw(NUMBER)
    else:
        return data.draw(VALUE)
    return reply


def _text(raw: object, as_text: bool) -> object:
    if not as_text:
        return raw
    try:
        return json.dumps(raw)
    except (TypeError, ValueError):
        return raw


@pytest.mark.slow
@settings(max_examples=700, derandomize=True, deadline=None)
@given(data=st.data(), as_text=st.booleans())
def test_hostile_formulations_are_a_clear_error_or_clamped(data: st.DataObject, as_text: bool) -> None:
    raw = _text(_mutate_formulation(data), as_text)
    try:
        reply, program, notes = check_formulation(parse_formulation(raw), PUSH, K, T)
    except ReasoningError as exc:
        assert 0 < len(str(exc)) <= 700
        return
    for s in reply.stages:
        assert program.has(s.cost) and program.has(s.done)
        assert 0.2 <= s.timeout_s <= MAX_TIMEOUT_S and math.isfinite(s.hold_s)
        assert s.press_n is None or abs(s.press_n) <= PUSH.robot.force_limit_n
    for r in reply.regions:
        assert 0 < r.radius <= MAX_RADIUS_M and abs(math.hypot(*r.normal) - 1) < 1e-9


def _adapt_request() -> AdaptRequest:
    history = AttemptHistory(attempt=1, stages=[], failed_stage="press", max_force_n=3.0, mean_press_force_n=3.2,
                             object_travel_m={"box": 0.1}, object_tilt_deg={"box": 1.0})
    return AdaptRequest(task=PUSH.task, scene=PUSH, beliefs=PUSH.priors, source=GOOD.source, stages=GOOD.stages,
                        regions=GOOD.regions, knobs=GOOD.knobs, history=[history])


AREQ = _adapt_request()
BELIEF = st.fixed_dictionaries({"mass_kg": NUMBER, "friction": NUMBER}, optional={"material": VALUE})


def _mutate_adaptation(data: st.DataObject) -> object:
    what = data.draw(st.sampled_from(["beliefs", "code", "stages", "junk", "whole"]))
    reply: dict = {"diagnosis": data.draw(st.one_of(st.text(max_size=40), VALUE))}
    if what == "beliefs":
        reply["beliefs"] = data.draw(st.dictionaries(st.sampled_from(["box", "wall", "ghost", ""]),
                                                     st.one_of(BELIEF, VALUE), max_size=2))
    elif what == "code":
        reply["source"] = data.draw(st.one_of(st.sampled_from(HOSTILE_CODE), st.text(max_size=60)))
    elif what == "stages":
        reply["stages"] = data.draw(st.one_of(VALUE, st.just([{"name": "x", "cost": "nope", "done": "nope"}])))
    elif what == "junk":
        reply[data.draw(st.text(min_size=1, max_size=8))] = data.draw(VALUE)
    else:
        return data.draw(VALUE)
    return reply


@pytest.mark.slow
@settings(max_examples=600, derandomize=True, deadline=None)
@given(data=st.data(), as_text=st.booleans())
def test_hostile_adaptations_are_a_clear_error_or_clamped(data: st.DataObject, as_text: bool) -> None:
    raw = _text(_mutate_adaptation(data), as_text)
    try:
        reply, plan, program, notes = check_adaptation(parse_adaptation(raw), AREQ, K, T)
    except ReasoningError as exc:
        assert 0 < len(str(exc)) <= 700
        return
    if reply.beliefs is not None:
        for name, b in reply.beliefs.items():
            assert name == "box" and b.mass_kg > 0 and FRICTION_BOUNDS[0] <= b.friction <= FRICTION_BOUNDS[1]
    assert plan.stages


def test_negative_mass_and_nan_friction_are_clamped_or_refused() -> None:
    clamped, _, _, notes = check_adaptation(parse_adaptation({"beliefs": {"box": {"mass_kg": -3, "friction": 0.4}}}),
                                            AREQ, K, T)
    assert clamped.beliefs["box"].mass_kg > 0 and any("mass_kg" in n for n in notes)
    try:
        check_adaptation(parse_adaptation('{"beliefs": {"box": {"mass_kg": 0.3, "friction": NaN}}}'), AREQ, K, T)
    except ReasoningError as exc:
        assert "finite" in str(exc)
    else:
        raise AssertionError("NaN friction was accepted")


def test_code_that_never_terminates_cannot_be_written() -> None:
    for src in HOSTILE_CODE[:8]:
        reply = GOOD.model_copy(update={"source": src})
        try:
            check_formulation(reply, PUSH, K, T)
        except ReasoningError as exc:
            assert "refused" in str(exc) or "defines" in str(exc)
        else:
            raise AssertionError(f"accepted: {src[:40]!r}")


# --- the instruction language: random word salads over the language's own words and the scene's names -------------

LANGUAGE_SCENES = ("push", "clutter", "board", "tall", "curb", "puck", "two", "cyl", "around", "roll")


@settings(max_examples=400, deadline=None, derandomize=True)
@given(scene=st.sampled_from(LANGUAGE_SCENES), words=st.lists(st.sampled_from(
    "push pick up put place press flip tip slide roll hold still the a box board puck cylinder wall curb disc goal "
    "post red green blue wooden against onto on to away from left right forward back by 5 cm 10 n for 2 seconds "
    "with force of don't not without lifting touching it then and over edge table using as fixture gently teapot "
    ", . until sticks out handle its".split()), min_size=1, max_size=14))
def test_any_word_salad_is_a_plan_or_one_line_refusal(scene: str, words: list[str]) -> None:
    """Never a crash: each instruction is planned (and its code compiles) or refused with one line."""
    from kintsugi.methods.coral.formulate import request_variables
    from kintsugi.methods.coral.nouns import NotUnderstood
    from kintsugi.sandbox import CostProgram
    from tests.methods.coral.language_scenes import scene_request

    req = scene_request(scene, " ".join(words))
    try:
        reply = compose(req)
    except NotUnderstood as exc:
        assert str(exc).startswith("not understood") and "\n" not in str(exc)
        return
    program = CostProgram.compile(reply.source, request_variables(req))
    assert all(program.has(s.cost) and program.has(s.done) for s in reply.stages)
