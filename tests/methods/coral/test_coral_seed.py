"""A stage's plan restarts from its goal when the code gives one (`<cost>_seed_<axis>`): the edge pick's stages
seed the servos at their targets, read from the geometry and the state at stage entry, and a seed that is not
one finite number is a recorded cost-code error, never a silent wrong command."""

from __future__ import annotations

import math

import numpy as np
import pytest

from kintsugi.methods.coral.stages import CodeTiming, CostCodeError, build_stages
from kintsugi.methods.coral.types import FormulationReply, StageSpec
from kintsugi.methods.coral.costlib import DEFAULT_KNOBS, compose
from kintsugi.methods.coral.formulate import request_variables
from kintsugi.sandbox import CostProgram

from tests.coral_fixtures import coral_scene


@pytest.fixture(scope="module")
def board_trial():  # noqa: ANN201 - (ctx, cfg, obs, request)
    ctx, cfg, obs, req, world = coral_scene("push-pick-board", 3)
    yield ctx, cfg, obs, req
    world.close()


def _stages(reply: FormulationReply, program: CostProgram, ctx, cfg, obs) -> dict:  # noqa: ANN001
    made = build_stages(reply, program, ctx.known, cfg, 0, CodeTiming())
    return {spec.name: factory(obs) for spec, factory in zip(reply.stages, made)}


def test_the_edge_pick_seeds_each_move_at_its_goal(board_trial) -> None:  # noqa: ANN001
    ctx, cfg, obs, req = board_trial
    reply = compose(req)
    program = CostProgram.compile(reply.source, request_variables(req))
    stages = _stages(reply, program, ctx, cfg, obs)
    k, edge = DEFAULT_KNOBS, cfg.table.edge_x_m
    tcp, b = obs.ee[:3], obs.objects["board"]
    from kintsugi.worlds.contact.world import yaw_of

    yaw = float(yaw_of(b.quat))
    # reach: above the pinch point past the edge, the hand turned with the board (stage entry = this state here)
    reach = stages["reach"].seed_plan
    assert reach[0] == pytest.approx(edge + k["pinch_past_edge_m"]) and reach[2] == pytest.approx(k["travel_z_m"])
    assert reach[1] == pytest.approx(b.pos[1] + (edge + k["pinch_past_edge_m"] - b.pos[0]) * math.tan(yaw))
    assert reach[3] == pytest.approx(yaw)
    # descend: straight down where the hand is; lift: up and back over the table; grasp and hold: where it is
    assert stages["descend"].seed_plan == pytest.approx({0: tcp[0], 1: tcp[1], 2: k["under_edge_z_m"]})
    assert stages["lift"].seed_plan == pytest.approx({0: tcp[0] - 0.03, 1: tcp[1], 2: k["edge_lift_z_m"]})
    here = {0: tcp[0], 1: tcp[1], 2: tcp[2], 3: float(obs.ee[3])}
    assert stages["hold"].seed_plan == pytest.approx(here) and stages["grasp"].seed_plan == pytest.approx(here)
    assert stages["back-off"].seed_plan == pytest.approx({0: tcp[0] - 0.03, 1: tcp[1], 2: k["travel_z_m"], 3: 0.0})
    # the push keeps the plan it inherits (no seed functions)
    assert stages["push"].seed_plan == {}


def test_a_seed_must_be_one_finite_number(board_trial) -> None:  # noqa: ANN001
    ctx, cfg, obs, req = board_trial
    variables = request_variables(req)
    base = "def c(tcp):\n    return 0.0 * tcp[..., 0]\n\n\ndef d(tcp):\n    return tcp[..., 0] > 9.0\n\n\n"
    reply = FormulationReply(source="", stages=[StageSpec(name="s", cost="c", done="d")])
    for body, ok in (("start_tcp[2] + 0.05", True), ("start_tcp", False), ("log(0.0 * start_tcp[0] - 1.0)", False)):
        program = CostProgram.compile(base + f"def c_seed_z(start_tcp):\n    return {body}\n", variables)
        if ok:
            assert _stages(reply, program, ctx, cfg, obs)["s"].seed_plan == pytest.approx({2: obs.ee[2] + 0.05})
        else:
            with pytest.raises(CostCodeError, match="seed"):
                _stages(reply, program, ctx, cfg, obs)
    # no seed functions: the stage keeps the plan it inherits
    assert _stages(reply, CostProgram.compile(base, variables), ctx, cfg, obs)["s"].seed_plan == {}
    assert np.isfinite(obs.ee).all()
