"""The re-planning baselines (inner-monologue, doremi, code-as-monitor) and their verify role: the reasoner is
asked at run time (counted as runtime calls), a failure makes the composer plan again from what is observed
now, keeping only history facts it verified (a pour already done)."""

from __future__ import annotations

import pytest

from kintsugi.methods.agentchord.method import metrics_of
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.taskgraph_types import VerifyRequest
from kintsugi.reasoning.verifier import embedded_verify
from kintsugi.trial import TrialSpec, run_trial
from tests.taskgraph_fixtures import seen_scene

HOLD = {"kind": "touching", "arm": "right", "object": "bottle"}
UP = {"kind": "upright", "object": "bottle", "tol_deg": 15}


def _verify(constraints, **scene):
    objects, arms = seen_scene(**scene)
    return embedded_verify(VerifyRequest(task="pour", subgoal="bottle in hand", constraints=constraints,
                                         objects=objects, arms=arms))


def test_the_embedded_verifier_reads_the_perceived_scene() -> None:
    assert _verify([HOLD], bottle_held_by="right").success
    no = _verify([HOLD])
    assert not no.success and "touching" in no.explanation
    assert not _verify([UP], bottle_upright=False).success  # no axis was given: unseen counts as not verified
    assert _verify([{"kind": "near", "a": {"entity": "bottle"}, "b": {"entity": "cup"}, "tol": 0.5}]).success
    with pytest.raises(BadReply, match="not a template"):
        _verify([{"kind": "teleported", "object": "bottle"}])


def _trial(method: str, seed: int, p: float = 0.1):
    return run_trial(TrialSpec(task="pour-single", method=method, variant="default", condition="drop", seed=seed,
                               overrides={"disturbance.drop_p": p}))


def test_inner_monologue_verifies_every_subgoal_at_run_time() -> None:
    r = _trial("inner-monologue", 2)  # seed 2: no drop
    m = metrics_of(r)
    assert r.success and m.planning_reasoning_calls == 1 and m.recoveries == 0
    assert m.runtime_reasoning_calls == 6 == sum(1 for c in r.transcript if c["role"] == "verify")


@pytest.mark.parametrize("method", ["doremi", "code-as-monitor"])
def test_a_drop_makes_the_reasoner_plan_again(method: str) -> None:
    r = _trial(method, 3)  # the bottle drops at the end of the lift
    m = metrics_of(r)
    assert r.success and r.framework_success
    assert [e.detail for e in r.events if e.kind == "replan"] and m.recoveries == 1
    roles = [c["role"] for c in r.transcript]
    assert roles.count("composer") == 2 and m.runtime_reasoning_calls > 1
    assert m.modelled_execution_time_s == pytest.approx(r.sim_time + 5.0 * len(roles), abs=1e-3)
