"""The endpoint preflight against the fake server: it stops a campaign before its first trial with one line
naming what the endpoint cannot do and which method's roles need it, or lets it run with notes."""

from __future__ import annotations

import base64
import re

import pytest

from tests.fake_openai_server import FakeOpenAIServer, content
from kintsugi.testing.peg_requests import judge_request
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.reasoning import first_requests, make_reasoner
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.images import png_size
from kintsugi.reasoning.preflight import CapabilityError, image_use, prepare, preflight, roles_of
from kintsugi.reasoning.roles import ROLES, ask
from kintsugi.core.registry import METHODS
from kintsugi.core.plugins import load_builtins


def spec(server: FakeOpenAIServer, task: str = "peg-insertion", method: str = "recovery", variant: str = "square",
         condition: str = "none", mode: str = "auto", **options: object) -> TrialSpec:
    return TrialSpec(task=task, method=method, variant=variant, condition=condition, seed=0,
                     reasoner=ReasonerSettings(backend="openai", model="m", base_url=server.base_url, timeout_s=5,
                                               max_retries=0, structured_output=mode, options=options))


def test_methods_ask_the_roles_of_their_own_package() -> None:
    load_builtins()
    assert [r.name for r in roles_of(METHODS.get("recovery"))] == ["analyze", "judge", "plan"]
    assert {r.name for r in roles_of(METHODS.get("coral"))} == {"priors", "formulate", "adapt"}
    assert roles_of(METHODS.get("expert")) == []
    judge, = [r for r in roles_of(METHODS.get("recovery")) if r.name == "judge"]
    assert image_use(judge) == "always"
    assert {image_use(r) for r in roles_of(METHODS.get("agentchord"))} == {"optional"}


def test_a_text_only_endpoint_stops_peg_and_agentchord_before_any_trial() -> None:
    with FakeOpenAIServer(images=False) as server:
        with pytest.raises(CapabilityError) as info:
            preflight([spec(server)])
        line = str(info.value)
        assert "\n" not in line and "takes no images" in line and "image input is not supported" in line
        assert "recovery's analyze, judge send camera images" in line and "images=measurements" in line
        with pytest.raises(CapabilityError, match="agentchord's arranger, composer, verify send camera images"):
            preflight([spec(server, "pour-single", "agentchord", "default", "drop")])
        assert server.requests == []  # only probes were sent


def test_measurements_instead_of_images_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(first_requests, "IDLE_S", 2.0)
    with FakeOpenAIServer(images=False) as server:
        notes = preflight([spec(server, "flip-box", "coral", "default", "all", images="measurements")])
        assert any("does not report its context length" in n for n in notes)
        assert server.requests == []  # only probes and counts were sent


def test_strict_mode_needs_the_strict_options_auto_only_notes_them() -> None:
    with FakeOpenAIServer(refuse={"json_schema"}, refuse_status=500) as server:
        with pytest.raises(CapabilityError, match="does not honour strict response_format json_schema .*HTTP 500.*"
                                                  "recovery's analyze, judge need it with --structured-output strict"):
            preflight([spec(server, mode="strict")])


def test_the_first_requests_are_counted_as_sent_and_the_findings_reach_the_trials() -> None:
    with FakeOpenAIServer(refuse={"json_schema"}, refuse_status=500) as server:
        notes, (prepared,) = prepare([spec(server, image_max_px=96)])
        assert any("recovery's analyze, judge will ask for JSON in text" in n for n in notes)
        counted = [p for p in server.probes if p["messages"][0]["role"] == "system"]
        judge, = [p for p in counted if _text(p).startswith(ROLES.get("judge").prompt_text())]
        user = judge["messages"][1]["content"]
        assert "# Request" in user[0]["text"] and "# Answer format" in user[-1]["text"]  # text mode, as it will go
        pngs = [base64.b64decode(p["image_url"]["url"].split(",", 1)[1]) for p in user if p["type"] == "image_url"]
        assert pngs and all(max(png_size(png)) <= 96 for png in pngs)  # at the size sent
        # the embedded judge passes this trial: the roles asked only after a failure are counted by their prompts
        assert any("recovery's analyze, plan: not asked in the dry run of peg-insertion/recovery/square/none/0" in n
                   for n in notes), notes
        assert server.requests == []
    learnt = prepared.reasoner.options["learnt"]
    assert set(learnt["text_mode"]) == {"json_schema"} and "HTTP 500" in learnt["text_mode"]["json_schema"]
    assert learnt["images"] == "sent" and prepared.key == spec(server).key
    with FakeOpenAIServer(refuse={"json_schema"}, refuse_status=500) as worker_server:
        options = {**prepared.reasoner.options, "preflight": False}
        settings = prepared.reasoner.model_copy(update={"base_url": worker_server.base_url, "options": options})
        rec = RecordingReasoner(make_reasoner(settings))
        worker_server.push(content({"success": False, "explanation": "the peg is not in the hole"}))
        ask(rec, "judge", judge_request())
        assert worker_server.refused == 0  # a worker starts in text mode: nothing is refused again
        assert rec.records[-1].output_mode == "text" and "text mode from the preflight" in rec.records[-1].output_note


def _text(probe: dict) -> str:
    user = probe["messages"][1]["content"]
    return user if isinstance(user, str) else user[0]["text"]


def test_a_first_request_longer_than_the_context_stops_the_campaign_naming_its_large_part() -> None:
    with FakeOpenAIServer(context=2000) as server:
        with pytest.raises(CapabilityError) as info:
            preflight([spec(server, images="measurements")])
    line = str(info.value)
    assert "\n" not in line
    assert re.search(r"recovery's judge first request on peg-insertion/recovery/square/none/0 is [\d,]+ tokens, plus "
                     r"256 for the reply, against the model's 2,000-token context \(as the server said\); by part: "
                     r"(request data|system prompt|role prompt|answer format) [\d,]+, .*; the (request data|system "
                     r"prompt|role prompt|answer format) is the largest; use a model with a longer context", line), line


def test_without_a_trial_the_fixed_prompts_are_counted() -> None:
    load_builtins()
    with FakeOpenAIServer() as server:
        reasoner = make_reasoner(ReasonerSettings(backend="openai", model="m", base_url=server.base_url,
                                                  max_retries=0, options={"context_tokens": 1024}))
        with pytest.raises(CapabilityError, match=r"recovery's \w+ needs at least [\d,]+ tokens before its request "
                                                  r"data .* but the model's context is 1,024 \(reasoner.options"):
            reasoner.preflight({"recovery": roles_of(METHODS.get("recovery"))})


def test_preflight_can_be_turned_off_and_skips_offline_backends() -> None:
    with FakeOpenAIServer(images=False) as server:
        assert preflight([spec(server, preflight=False)]) == []
        offline = spec(server).model_copy(update={"reasoner": ReasonerSettings()})
        assert preflight([offline]) == [] and server.probes == []
