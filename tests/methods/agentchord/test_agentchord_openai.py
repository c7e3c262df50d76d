"""A whole agentchord trial with the openai backend against the local fake server: the composer and arranger
are asked once each (images attached), nothing at run time; an endpoint that cannot give a usable graph ends
the trial with a recorded reasoning error, never a crash."""

from __future__ import annotations

import json

from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.observe import seen_arms, seen_objects
from kintsugi.methods.agentchord.method import metrics_of
from kintsugi.methods.agentchord.arranger import embedded_arrange
from kintsugi.methods.agentchord.composer import embedded_compose
from kintsugi.methods.agentchord.types import ArrangerRequest, ComposerRequest
from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.registry import TASKS
from kintsugi.core.runner import run_trial
from tests.fake_openai_server import FakeOpenAIServer, content

load_builtins()


def _spec(server: FakeOpenAIServer) -> TrialSpec:
    return TrialSpec(task="pour-single", method="agentchord", variant="default", condition="none", seed=0,
                     reasoner=ReasonerSettings(backend="openai", model="scripted", base_url=server.base_url,
                                               timeout_s=5.0, max_retries=0))


def _model_replies() -> tuple[dict, dict]:
    """What a good model would answer for this trial's first observation (the embedded answers, as JSON)."""
    from kintsugi.worlds.tabletop.robot import TabletopRobot

    task = TASKS.get("pour-single").factory()
    world, *_ = task.build(task.config({}), "none", 0)
    obs = TabletopRobot(world).observation(images=False)
    world.close()
    objects, arms = seen_objects(obs.objects), seen_arms(obs.arms)
    req = ComposerRequest(task=task.spec.instruction, goal=list(task.spec.goal), objects=objects, arms=arms,
                          domain=TABLETOP_DOMAIN)
    composed = embedded_compose(req)
    arranged = embedded_arrange(ArrangerRequest(task=req.task, graph=composed.graph, node_facts=composed.node_facts,
                                                edge_operators=composed.edge_operators, objects=objects, arms=arms,
                                                domain=TABLETOP_DOMAIN))
    return json.loads(composed.model_dump_json()), json.loads(arranged.model_dump_json())


def test_agentchord_trial_over_the_openai_protocol(fake_openai: FakeOpenAIServer) -> None:
    composed, arranged = _model_replies()
    fake_openai.push(content(composed), content(arranged))
    rec = run_trial(_spec(fake_openai))
    assert rec.error is None and rec.success and rec.framework_success
    assert [(c["role"], c["backend"]) for c in rec.transcript] == [("composer", "openai"), ("arranger", "openai")]
    assert metrics_of(rec).runtime_reasoning_calls == 0 and len(fake_openai.requests) == 2
    first = fake_openai.requests[0]["messages"][-1]["content"]
    assert sum(1 for part in first if isinstance(part, dict) and part.get("type") == "image_url") == 2  # top, front


def test_an_unusable_graph_is_a_recorded_reasoning_error(fake_openai: FakeOpenAIServer) -> None:
    bad = {"graph": {"start": "a", "goal": "a", "nodes": [{"id": "a"}]}, "reasoning": "nothing to do"}
    fake_openai.push(content(bad), content("not even JSON"))
    rec = run_trial(_spec(fake_openai))
    assert rec.error is not None and "composer" in rec.error and not rec.framework_success
    assert rec.reasoning_errors == 1 and rec.transcript[-1]["role"] == "composer"
    assert "start and goal are the same node" in json.dumps(fake_openai.requests[1]["messages"])
