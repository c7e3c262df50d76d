"""The instruction suite (instructions.yaml): every instruction gives exactly the plan of primitives it lists
(primitive, object and key parameters) or the refusal it lists; none is read any other way. Every plan's cost
code compiles in the cost language, with and without a contact strategy, and the new primitives' code passes the
sandbox's probe."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.coral.costlib import compose
from kintsugi.methods.coral.formulate import check_formulation, embedded_formulation, request_variables
from kintsugi.methods.coral.nouns import NotUnderstood
from kintsugi.methods.coral.plan import plan_instruction
from kintsugi.sandbox import CostProgram
from tests.methods.coral.language_scenes import scene_request

SUITE = yaml.safe_load((Path(__file__).parent / "instructions.yaml").read_text())


def test_the_suite_is_large_and_mixed() -> None:
    understood = [x for x in SUITE if "plan" in x]
    refused = [x for x in SUITE if "refuse" in x]
    assert len(SUITE) >= 100 and len(understood) + len(refused) == len(SUITE)
    assert len(understood) >= 60 and len(refused) >= 30
    texts = " ".join(x["text"].lower() for x in SUITE)
    for word in ("don't", "without", "left", "right", "away from", " cm", " n ", "seconds", "onto", "using"):
        assert word in texts + " ", word


@pytest.mark.parametrize("item", SUITE, ids=[f"{i}-{x['text'][:40]}" for i, x in enumerate(SUITE)])
def test_each_instruction_reads_as_listed(item: dict) -> None:
    req = scene_request(item["scene"], item["text"])
    if "refuse" in item:
        with pytest.raises(NotUnderstood) as exc:
            plan_instruction(req)
        assert item["refuse"] in str(exc.value)
        with pytest.raises(ReasoningError, match="embedded formulation: not understood"):
            embedded_formulation(req)  # the role's refusal: one line the method records as a failed trial
        assert "\n" not in str(exc.value)
        return
    plan = plan_instruction(req)
    assert plan.primitives == item["plan"]
    assert len(plan.notes) == item.get("notes", 0)
    for contact in (True, False):
        r = scene_request(item["scene"], item["text"], contact=contact)
        reply = compose(r)
        program = CostProgram.compile(reply.source, request_variables(r))
        for st in reply.stages:
            assert program.has(st.cost) and program.has(st.done)
        assert contact or reply.regions == []
        assert reply.reasoning.startswith("Plan: " + "; ".join(item["plan"]))


@pytest.mark.slow
@pytest.mark.parametrize("scene,text", [
    ("puck", "Slide the puck onto the green disc."),
    ("push", "Push the box 5 cm to the left and then push it forward 5 cm."),
    ("cyl", "Topple the wooden cylinder away from the wall."),
    ("two", "Push the blue box away from the red box by 6 cm."),
])
def test_new_primitives_pass_the_sandbox(scene: str, text: str) -> None:
    for contact in (True, False):
        req = scene_request(scene, text, contact=contact)
        checked, program, notes = check_formulation(compose(req), req, 16, 5)
        assert notes == [] and len({s.name for s in checked.stages}) == len(checked.stages)


def test_a_slide_is_done_only_on_its_goal_and_at_rest() -> None:
    import numpy as np

    from kintsugi.methods.coral.formulate import sample_env

    req = scene_request("push", "Push the box 10 cm to the left.")
    reply = compose(req)
    program = CostProgram.compile(reply.source, request_variables(req))
    env = sample_env(req, ())
    first = env["first_box_pos"]
    env.update(box_vel=np.zeros(3), box_pos=first + np.array([0.0, 0.10, 0.0]))
    assert bool(program.call("slide_done", env))
    env["box_pos"] = first + np.array([0.0, 0.05, 0.0])  # half way
    assert not bool(program.call("slide_done", env))
    env["box_pos"] = first + np.array([0.10, 0.0, 0.0])  # 10 cm, the wrong way
    assert not bool(program.call("slide_done", env))
    env.update(box_pos=first + np.array([0.0, 0.10, 0.0]), box_vel=np.array([0.0, 0.05, 0.0]))  # still sliding
    assert not bool(program.call("slide_done", env))


def test_a_push_round_a_post_keeps_clear_of_it_and_goes_by_a_way_point_beside_it() -> None:
    import numpy as np

    from kintsugi.methods.coral.formulate import sample_env

    req = scene_request("around", "Push the red box onto the green disc without touching the grey post.")
    plan = plan_instruction(req)
    via = next(p for p in plan.primitives if "via=" in p)
    x, y = (float(v) for v in via.split("via=")[1].split()[0].split(","))
    post = req.fixtures[0]
    assert post.lo_m[0] <= x <= post.hi_m[0] and abs(y) > post.hi_m[1] + 0.05  # beside the post, clear of it
    reply = compose(req)
    program = CostProgram.compile(reply.source, request_variables(req))
    env = sample_env(req, ())
    on_post = np.array([0.10, 0.0, 0.025])
    assert float(program.call("clear_post_box", {**env, "box_pos": on_post})) > 0.05
    assert float(program.call("clear_post_box", {**env, "box_pos": np.array([0.10, 0.12, 0.025])})) == 0.0
    assert float(program.call("clear_post_hand", {**env, "tcp": np.array([0.10, 0.03, 0.05])})) > 0.0
    # told nothing about the post, the push goes straight
    straight = plan_instruction(scene_request("around", "Push the red box onto the green disc."))
    assert not any("via=" in p for p in straight.primitives)


def test_without_a_contact_strategy_the_grasp_has_no_side_or_height_chosen() -> None:
    with_strategy = compose(scene_request("clutter", "Pick up the box."))
    blind = compose(scene_request("clutter", "Pick up the box.", contact=False))
    assert "start_cube0_pos" in with_strategy.source and "start_cube0_pos" not in blind.source
    assert "def box_aim(start_yaw):" in blind.source and "finger_length / 3.0" not in blind.source
    assert [s.name for s in blind.stages] == [s.name for s in with_strategy.stages]


def test_without_a_contact_strategy_the_overhang_is_not_pinched_from_below() -> None:
    text = "Push the cutting board until its handle sticks out over the table edge, then pick the board up by the handle."
    coral = compose(scene_request("board", text))
    blind = compose(scene_request("board", text, contact=False))
    assert "under_cost" in coral.source and "under_cost" not in blind.source
    assert [s.name for s in blind.stages] == ["approach", "push", "back-off", "reach", "descend", "grasp", "lift", "hold"]
