"""Cost code whose work depends on the state passes its probe and is stopped in the control loop.

The heavy branch runs only on states the loop meets (the plan's first knot repeats the command in
force, so `step_change` is exactly 0 there; the probe's samples never are): the probe measures
microseconds, the loop's first call would take seconds. The loop's bound stops that call within a
second and the attempt ends with a recorded sandbox error (`overrun`), never a stall.
"""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

from kintsugi.core.errors import SandboxError
from kintsugi.core.log import TrialLog
from kintsugi.methods.coral.formulate import check_formulation
from kintsugi.methods.coral.method import probe_limits
from kintsugi.methods.coral.stages import CodeTiming, CostCodeError, build_stages
from kintsugi.methods.coral.types import FormulationReply, StageSpec
from kintsugi.methods.mppi.execute import run_attempt
from kintsugi.sandbox import CostProgram, LoopBound, ProbeLimits, probe
from kintsugi.sandbox.payloads import ENV, IN_LOOP, LOOP_K, LOOP_STATE, K
from kintsugi.worlds.contact.robot import ContactRobot
from kintsugi.worlds.contact.world import PlanningWorld

from tests.coral_fixtures import coral_scene

HEAVY = "\n".join("        y = smoothstep(tan(arctan2(y, y)), y, y)" for _ in range(110))
RUNAWAY = f'''def cost(tcp, step_change):
    y = tcp
    if min(step_change) < 1e-12:
{HEAVY}
        return norm(y) + 0.0 * step_change
    return norm(tcp) + step_change


def done(tcp):
    return tcp[2] < -1.0
'''


@pytest.mark.parametrize("source", IN_LOOP, ids=range(len(IN_LOOP)))
def test_a_state_dependent_payload_passes_the_probe_and_is_stopped_in_the_loop(source: str) -> None:
    report = probe(source, set(ENV), {"cost": (K,)}, ENV, ProbeLimits(wall_s=60.0))
    program = CostProgram.compile(source, set(ENV))
    program.probed_s.update(report.seconds_per_call)
    assert program.bounded_call("cost", ENV, (K,)).shape == (K,)  # the probe's states: fast, as probed
    t0 = time.perf_counter()
    with pytest.raises(SandboxError) as exc:
        program.bounded_call("cost", LOOP_STATE, (LOOP_K,))
    assert time.perf_counter() - t0 < 1.0
    assert exc.value.kind == "overrun" and "depends on the state" in str(exc.value)


def test_the_bound_leaves_an_honest_cost_alone_and_caps_an_unprobed_one() -> None:
    bound = LoopBound()
    assert bound.limit(None) == bound.budget_s and bound.limit(1e-5) == bound.floor_s
    assert bound.limit(0.004) == pytest.approx(50 * 0.004) and bound.limit(0.1) == bound.budget_s
    program = CostProgram.compile("def cost(tcp):\n    return mean(norm(tcp), axis=-1)", set(ENV))
    program.probed_s["cost"] = 1e-6
    for _ in range(50):
        assert np.all(np.isfinite(program.bounded_call("cost", LOOP_STATE, (LOOP_K,))))


def test_a_runaway_branch_ends_the_attempt_with_a_recorded_sandbox_error() -> None:
    ctx, cfg, obs, req, world = coral_scene("push-force", 5)
    try:
        samples, steps = 256, 50
        cfg = cfg.model_copy(update={"control": cfg.control.model_copy(update={"samples": samples})})
        reply = FormulationReply(source=RUNAWAY, stages=[StageSpec(name="go", cost="cost", done="done", timeout_s=3.0)],
                                 regions=[], knobs={}, reasoning="a state-dependent runaway")
        plan, program, _ = check_formulation(reply, req, samples, steps, probe_limits())  # the probe accepts it
        assert program.probed_s["cost"] < 0.05
        robot = ContactRobot(world)
        planning = PlanningWorld(cfg, ctx.known, {"box": _belief()})
        factories = build_stages(plan, program, ctx.known, cfg, 0, CodeTiming())
        with pytest.raises(CostCodeError, match="in the control loop") as exc:
            run_attempt(cfg, robot, planning, factories, TrialLog(), seed=0)
        stopped = float(re.search(r"after ([0-9.]+) s", str(exc.value)).group(1))
        assert stopped < 1.0, str(exc.value)
        assert robot.sim_time < 0.2  # the first planning step: the loop never ran on with it
    finally:
        world.close()


def _belief():  # noqa: ANN202
    from kintsugi.worlds.contact.objects import Physics

    return Physics(mass_kg=0.5, friction=0.5)
