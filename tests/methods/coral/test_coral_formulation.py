"""CoRAL's formulation and adaptation roles: the embedded cost library chooses skills from the instruction and
fills them from the geometry (not from the task's name), its code passes the sandbox, the embedded adaptation
adopts a sysid fit only when it explains the log better, and the openai protocol repairs bad cost code once."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.coral.adapt import check_adaptation, embedded_adaptation
from kintsugi.methods.coral.types import AdaptRequest, AttemptHistory, ObjectState, StageOutcome, SysIdSummary
from kintsugi.methods.coral.costlib import compose
from kintsugi.methods.coral.formulate import check_formulation, embedded_formulation, request_variables, sample_env
from kintsugi.sandbox import CostProgram
from tests.coral_scenes import BOX, CLUTTER, CUBES, DISC, GREEN, PUSH, WALL, request

K, T = 16, 5
CURB = WALL.model_copy(update={"name": "curb"})


@pytest.mark.slow
def test_push_and_press_from_the_instruction_and_the_wall() -> None:
    reply = compose(PUSH)
    assert [s.name for s in reply.stages] == ["approach", "push", "press"]
    press = reply.stages[-1]
    assert press.press_n == 5.0 and press.press_axis == 0 and press.region == 0
    region = reply.regions[0]
    assert region.object == "box" and region.normal == (-1.0, 0.0, 0.0)  # the face turned away from the wall
    assert math.isclose(region.center[0], -BOX.size_m[0] / 2)
    checked, program, notes = check_formulation(reply, PUSH, K, T)
    assert notes == [] and program.has("press_cost")


def test_words_not_task_names_choose_the_skills() -> None:
    other = request("Shove the crate against the barrier, then press on it with 3 newtons.",
                    [BOX.model_copy(update={"name": "crate", "label": "crate"})],
                    [WALL.model_copy(update={"name": "barrier"})])
    reply = compose(other)
    assert [s.name for s in reply.stages] == ["approach", "push", "press"] and reply.stages[-1].press_n == 3.0
    assert "barrier_lo" in reply.source and "crate_hi" in reply.source
    # a wall on the -x side: push the other way, on the +x face
    west = request(PUSH.task, [BOX], [WALL.model_copy(update={"lo_m": (-0.2, -0.15, 0.0), "hi_m": (-0.17, 0.15, 0.06)})])
    r = compose(west)
    assert r.regions[0].normal == (1.0, 0.0, 0.0) and r.stages[-1].press_n == -5.0
    tall = BOX.model_copy(update={"size_m": (0.05, 0.07, 0.1)})
    assert [s.name for s in compose(request("Flip the box over onto its side.", [tall])).stages] == \
        ["approach", "tip", "withdraw", "settle"]
    flat_curb = compose(request("Flip the box up using the curb as a fixture.", [BOX], [CURB]))
    assert [s.name for s in flat_curb.stages] == ["approach", "push", "rise", "pivot", "lift-off",
                                                 "withdraw", "clear", "back", "settle"]
    assert len(flat_curb.regions) == 2 and flat_curb.regions[1].center[2] > flat_curb.regions[0].center[2]


def test_an_instruction_the_library_cannot_read_is_a_reasoning_error() -> None:
    with pytest.raises(ReasoningError, match="'teapot' is neither a word of the language nor a name in the scene"):
        embedded_formulation(request("Pick up the teapot.", [BOX]))
    with pytest.raises(ReasoningError, match="'admire the box': no verb the language knows"):
        embedded_formulation(request("Admire the box.", [BOX]))
    with pytest.raises(ReasoningError, match="'curb' is neither a word"):  # the scene's fixture is a wall
        embedded_formulation(request("Flip the box up using the curb as a fixture.", [BOX], [WALL]))


def test_without_a_contact_strategy_there_are_no_regions_and_no_contact_variable() -> None:
    blind = request(PUSH.task, [BOX], [WALL], contact=False)
    reply = compose(blind)
    assert reply.regions == [] and all(s.region is None for s in reply.stages)
    assert "contact" not in request_variables(blind)
    check_formulation(reply, blind, K, T)
    # the full plan's code reads `contact`: refused where there is no contact strategy
    with pytest.raises(ReasoningError, match="contact"):
        check_formulation(compose(PUSH), blind, K, T)


def _aim(req, cubes) -> float:  # noqa: ANN001
    r = request(req.task, [GREEN, *cubes], markers=[DISC])
    reply = compose(r)
    program = CostProgram.compile(reply.source, request_variables(r))
    env = sample_env(r, ())
    env["start_yaw"] = np.asarray(0.0)
    return float(program.call("box_aim", env))


def test_the_grasp_side_keeps_the_open_fingers_clear_of_the_cubes() -> None:
    # cubes beside the box along +-y: pinch across x (hand turned 90 deg)
    yaw = math.radians(GREEN.yaw_deg)

    def off(a: float, b: float) -> float:  # distance modulo pi (a pinch is symmetric)
        return abs((a - b + math.pi / 2) % math.pi - math.pi / 2)

    assert off(_aim(CLUTTER, CUBES), yaw + math.pi / 2) < 1e-9
    far = [c.model_copy(update={"pos_m": (c.pos_m[0] + 1.0, c.pos_m[1] + 1.0, c.pos_m[2])}) for c in CUBES]
    assert math.isclose(_aim(CLUTTER, far), yaw, abs_tol=1e-9)  # nothing near: the least turn
    stages = [s.name for s in compose(CLUTTER).stages]
    assert stages == ["reach", "descend", "grasp", "lift", "carry", "lower", "release", "withdraw"]


def _history(failed: str, first: float, last: float, press: float | None = None) -> AttemptHistory:
    return AttemptHistory(attempt=1, stages=[StageOutcome(name=failed, reached=False, seconds=5.0, cost_first=first,
                                                          cost_last=last, cost_min=last)],
                          failed_stage=failed, max_force_n=4.0, mean_press_force_n=press,
                          object_travel_m={"box": 0.1}, object_tilt_deg={"box": 0.0})


def _areq(history: AttemptHistory, sysid: SysIdSummary | None, refine: bool = True) -> AdaptRequest:
    plan = compose(PUSH)
    return AdaptRequest(task=PUSH.task, scene=PUSH, beliefs=PUSH.priors, source=plan.source, stages=plan.stages,
                        regions=plan.regions, knobs=plan.knobs, history=[history], sysid=sysid, refine_strategy=refine)


def test_embedded_adaptation_adopts_a_fit_only_when_it_explains_the_log_better() -> None:
    good = SysIdSummary(object="box", mass_kg=0.6, friction=0.42, loss_prior=1.2, loss_fit=0.01, windows=20)
    bad = good.model_copy(update={"loss_fit": 2.0})
    hist = _history("press", 10.0, 9.5, press=3.1)
    adopted = embedded_adaptation(_areq(hist, good))
    assert adopted.beliefs["box"].mass_kg == 0.6 and "World model" in adopted.diagnosis
    assert embedded_adaptation(_areq(hist, bad)).beliefs is None
    # a stalled press: the force error is weighed more and the code is written again with the new knobs
    assert adopted.knobs["w_force"] > compose(PUSH).knobs["w_force"] and adopted.source != compose(PUSH).source
    checked, plan, program, notes = check_adaptation(adopted, _areq(hist, good), K, T)
    assert program is not None and plan.knobs == adopted.knobs
    only_physics = embedded_adaptation(_areq(hist, good, refine=False))
    assert only_physics.source is None and only_physics.beliefs is not None


def test_formulation_over_the_openai_protocol_repairs_refused_code_once() -> None:
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.methods.coral.formulate import ask_formulation
    from kintsugi.reasoning.openai_backend import OpenAIReasoner
    from tests.fake_openai_server import FakeOpenAIServer, content

    good = json.loads(compose(PUSH).model_dump_json())
    evil = dict(good, source="import os\n" + good["source"])
    with FakeOpenAIServer() as server:
        server.push(content(evil), content(good))
        model = OpenAIReasoner(model="fake-llm", base_url=server.base_url, api_key_env="KINTSUGI_TEST_NO_SUCH_KEY")
        rec = RecordingReasoner(model)
        reply, program, notes = ask_formulation(rec, PUSH, K, T)
        second = server.requests[1]
    assert program.has("push_cost") and reply.stages[-1].press_n == 5.0
    assert "cost code refused" in json.dumps(second["messages"])  # the repair round quoted the sandbox
    assert rec.records[0].role == "formulate" and rec.records[0].attempts == 2


def test_the_press_lasts_as_long_as_the_instruction_says() -> None:
    timed = request("Push the box against the wall and press it with 4 N for 3.5 seconds.", [BOX], [WALL])
    assert compose(timed).knobs["hold_press_s"] == 3.5
    untimed = request("Push the box against the wall and press it with 4 N.", [BOX], [WALL])
    assert compose(untimed).knobs["hold_press_s"] == 2.0  # the library's default when the text names none


@pytest.mark.slow
def test_push_over_the_edge_then_pick_from_below() -> None:
    board = ObjectState(name="board", label="cutting board", size_m=(0.34, 0.16, 0.02), pos_m=(0.05, 0.01, 0.01),
                        yaw_deg=4.0, upright_deg=0.0)
    req = request("Push the cutting board until its handle sticks out over the table edge, then pick the board up "
                  "by the handle.", [board])
    reply = compose(req)
    assert [s.name for s in reply.stages] == ["approach", "push", "back-off", "reach", "descend", "grasp", "lift",
                                              "hold"]
    assert reply.regions[0].normal == (-1.0, 0.0, 0.0) and reply.stages[1].region == 0  # pushed on its back face
    assert "table_edge_x" in reply.source and "board_hi" in reply.source  # reads the edge and the bounds, no numbers
    checked, program, notes = check_formulation(reply, req, K, T)
    assert notes == [] and program.has("edge_push_cost") and program.has("under_cost")
    # the same words with a different object and a reworded instruction choose the same skill
    tray = board.model_copy(update={"name": "tray", "label": "serving tray"})
    again = compose(request("Slide the serving tray over the edge of the table, then lift it.", [tray]))
    assert [s.name for s in again.stages] == [s.name for s in reply.stages] and "tray_hi" in again.source


@pytest.mark.slow
def test_the_pivot_counts_as_done_only_with_the_box_down_on_the_table() -> None:
    """A box turned upright but balanced on the curb's top is not done (the false successes of flip-wall):
    the pivot's own check wants it turned, still and down on the table the curb stands on."""
    req = request("Flip the box up using the curb as a fixture.", [BOX], [CURB])
    reply = compose(req)
    checked, program, notes = check_formulation(reply, req, K, T)
    assert [s.name for s in reply.stages][-5:] == ["lift-off", "withdraw", "clear", "back", "settle"]
    settle = reply.stages[-1]
    assert settle.done == "settle_done" and settle.hold_s >= 1.0
    env = sample_env(req, ())
    on_end = np.array([1.0, 0.0, 0.0])  # up axis turned 90 degrees
    env.update({"box_up": on_end, "box_vel": np.zeros(3), "box_spin": np.asarray(0.0)})
    env["box_lo"] = np.array([0.15, -0.03, 0.0])
    assert bool(program.call("settle_done", env))
    env["box_lo"] = np.array([0.19, -0.03, 0.015])  # standing on the curb's top
    assert not bool(program.call("settle_done", env))
    env["box_lo"] = np.array([0.15, -0.03, 0.0])
    slant = np.radians(10.0)  # over on its top but propped on the curb: one end up, creeping
    env["box_up"] = np.array([np.sin(slant), 0.0, -np.cos(slant)])
    assert not bool(program.call("settle_done", env))
    env["box_up"] = np.array([0.0, 0.0, -1.0])  # lying on its top
    assert bool(program.call("settle_done", env))
    env["box_lo"] = np.array([0.15, -0.03, 0.0])
    env["box_up"] = np.array([0.0, 0.0, 1.0])  # still flat
    assert not bool(program.call("settle_done", env))
    # a box on the curb's top is pushed on off it; one already on the table needs nothing more
    assert bool(program.call("clear_done", env))
    env["box_lo"] = np.array([0.19, -0.03, 0.015])
    assert not bool(program.call("clear_done", env))
    # the lift-off and the withdraw restart their plans at their goals
    assert program.has("lift_off_cost_seed_z") and program.has("withdraw_cost_seed_x")


def test_a_pivot_that_did_not_come_to_rest_turns_further_and_is_not_a_dropped_grasp() -> None:
    curb = request("Flip the box up using the curb as a fixture.", [BOX], [CURB])
    plan = compose(curb)
    hist = _history("settle", 1.0, 1.0).model_copy(update={"touch_lost_while_held": True})
    areq = AdaptRequest(task=curb.task, scene=curb, beliefs=curb.priors, source=plan.source, stages=plan.stages,
                        regions=plan.regions, knobs=plan.knobs, history=[hist], sysid=None, refine_strategy=True)
    reply = embedded_adaptation(areq)
    assert reply.knobs["pivot_deg"] == plan.knobs["pivot_deg"] + 10.0
    assert reply.knobs["touch_n"] == plan.knobs["touch_n"] and "pinch" not in reply.diagnosis
    assert reply.knobs["tip_deg"] == plan.knobs["tip_deg"]


@pytest.mark.slow
def test_a_place_is_done_only_with_the_box_left_on_the_disc_and_the_cubes_where_they_were() -> None:
    reply = compose(CLUTTER)
    checked, program, notes = check_formulation(reply, CLUTTER, K, T)
    env = sample_env(CLUTTER, ())
    env.update({"start_tcp": np.array([-0.05, 0.18, 0.06]), "tcp": np.array([-0.05, 0.18, 0.14]),
                "touch": np.zeros(2), "box_pos": np.array([-0.05, 0.17, 0.025]), "goal_xy": np.array([-0.05, 0.18]),
                "goal_radius": np.asarray(0.03)})
    cubes = [o.name for o in CLUTTER.objects if o.name != "box"]
    assert cubes
    env.update({f"{c}_pos": env[f"first_{c}_pos"] + np.array([0.005, -0.005, 0.0]) for c in cubes})
    assert bool(program.call("withdraw_up_done", env))
    env[f"{cubes[0]}_pos"] = env[f"first_{cubes[0]}_pos"] + np.array([0.03, 0.0, 0.0])  # a cube shoved 3 cm
    assert not bool(program.call("withdraw_up_done", env))
    env[f"{cubes[0]}_pos"] = env[f"first_{cubes[0]}_pos"]
    env["box_pos"] = np.array([-0.05, 0.23, 0.025])  # slid off the disc
    assert not bool(program.call("withdraw_up_done", env))
    descend = next(s for s in reply.stages if s.name == "descend")
    assert descend.noise_scale < 1.0 and program.has("descend_cost_seed_z")


@pytest.mark.slow
@pytest.mark.parametrize("body", ["return start_tcp", "return 1.0 / 0.0", "return undefined_name"])
def test_a_broken_seed_function_is_refused_before_the_loop(body: str) -> None:
    """`<cost>_seed_<axis>` functions are probed with the other stage functions: a vector, a division by zero or an
    unknown name is a BadReply at formulation, not a cost error at stage entry."""
    from kintsugi.reasoning.jsontext import BadReply

    reply = compose(PUSH)
    bad = reply.model_copy(update={"source": reply.source + f"\n\n\ndef push_cost_seed_x(start_tcp):\n    {body}\n"})
    with pytest.raises(BadReply, match="cost code refused"):
        check_formulation(bad, PUSH, K, T)
    good = reply.model_copy(update={"source": reply.source + "\n\n\ndef push_cost_seed_x(start_tcp):\n"
                                                              "    return start_tcp[0] + 0.01\n"})
    check_formulation(good, PUSH, K, T)
