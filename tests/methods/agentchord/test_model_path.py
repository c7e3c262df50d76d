"""System B's model path over the OpenAI protocol (the local fake server): the `verify` role the
re-planning baselines ask at run time, and one whole inner-monologue trial whose every call (composer,
verify, re-plans) goes over HTTP and is checked like any model's reply."""

from __future__ import annotations

import json

from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.methods.agentchord.types import SeenArm, SeenObject, VerifyReply, VerifyRequest
from kintsugi.methods.agentchord.verifier import ask_verify, embedded_verify
from kintsugi.reasoning import make_reasoner
from tests.fake_openai_server import FakeOpenAIServer, content

load_builtins()


def _openai(server: FakeOpenAIServer) -> ReasonerSettings:
    return ReasonerSettings(backend="openai", model="scripted", base_url=server.base_url, timeout_s=5.0,
                            max_retries=0)


def _verify_request() -> VerifyRequest:
    cup = SeenObject(name="cup", visible=True, centroid=(0.45, 0.0, 0.05), top_z=0.1, bottom_z=0.0, tilt_deg=2.0,
                     upright=True, extent=(0.1, 0.07, 0.07), axis=(0.0, 0.0, 1.0), n_points=400)
    arms = [SeenArm(name=a, tcp_pos=(0.2, y, 0.3), gripper_opening_m=0.08, gripper_closed=False)
            for a, y in (("left", 0.3), ("right", -0.3))]
    return VerifyRequest(task="Put the cup on the table.", subgoal="upright(cup)",
                         constraints=[{"kind": "upright", "object": "cup", "tol_deg": 15}], objects=[cup], arms=arms)


def test_verify_role_over_the_openai_protocol(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content({"explanation": "no verdict"}),  # missing `success`: one repair round
                     content({"success": True, "explanation": "the cup stands within 2 degrees"}))
    reply = ask_verify(make_reasoner(_openai(fake_openai)), _verify_request())
    assert reply == VerifyReply(success=True, explanation="the cup stands within 2 degrees")
    assert len(fake_openai.requests) == 2
    first = json.dumps(fake_openai.requests[0]["messages"])
    assert "upright(cup)" in first and "tol_deg" in first  # the model sees the sub-goal and its check
    assert "success" in json.dumps(fake_openai.requests[1]["messages"][-1])  # the repair names the field
    assert embedded_verify(_verify_request()).success  # the embedded verifier agrees on the same observation


def test_inner_monologue_trial_over_the_openai_protocol(fake_openai: FakeOpenAIServer) -> None:
    """The embedded trial's replies, served as a model's: the same calls in the same order, every one over
    HTTP, the same verdict."""
    spec = dict(task="pour-single", method="inner-monologue", variant="default", condition="none", seed=0)
    embedded = run_trial(TrialSpec(**spec))
    assert embedded.error is None and embedded.success
    roles = [c["role"] for c in embedded.transcript]
    assert roles[0] == "composer" and "verify" in roles
    fake_openai.push(*(content(c["reply"]) for c in embedded.transcript))
    rec = run_trial(TrialSpec(**spec, reasoner=_openai(fake_openai)))
    assert rec.error is None and rec.success and rec.framework_success
    assert [(c["role"], c["backend"]) for c in rec.transcript] == [(r, "openai") for r in roles]
    assert len(fake_openai.requests) == len(roles)
    composer = rec.transcript[0]
    assert composer["reply"]["goal"] and not composer["request"].get("goal")  # the instruction only: no goal in
    assert sorted(composer["reply"]["goal"]) == sorted(embedded.transcript[0]["reply"]["goal"])


def test_a_models_goal_is_checked_like_the_embedded_one(fake_openai: FakeOpenAIServer) -> None:
    """The composer's reply carries the goal a model read from the instruction; one naming an object the scene
    does not have, or a predicate the domain does not, gets a repair round naming it."""
    from kintsugi.methods.agentchord.composer import ask_compose, embedded_compose
    from tests.taskgraph_fixtures import composer_request, tabletop_vocab

    request = composer_request().model_copy(update={"goal": []})
    good = json.loads(embedded_compose(request).model_dump_json())
    reasoner = make_reasoner(_openai(fake_openai))
    for bad, named in ((["poured(bottle, glass)"], "glass"), (["spilled(bottle)"], "spilled"), ([], "no `goal`")):
        fake_openai.requests.clear()
        fake_openai.push(content({**good, "goal": bad}), content(good))
        _, reply = ask_compose(reasoner, request, tabletop_vocab())
        assert sorted(reply.goal) == sorted(good["goal"]) and len(fake_openai.requests) == 2
        assert named in json.dumps(fake_openai.requests[1]["messages"])
