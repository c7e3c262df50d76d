"""The endpoint preflight against the fake server: it stops a campaign before its first trial with one line
naming what the endpoint cannot do and which method's roles need it, or lets it run with notes."""

from __future__ import annotations

import pytest

from tests.fake_openai_server import FakeOpenAIServer
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.reasoning.preflight import CapabilityError, image_use, preflight, roles_of
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
    assert {image_use(r) for r in roles_of(METHODS.get("coral"))} == {"none"}


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


def test_measurements_instead_of_images_pass_and_coral_needs_none() -> None:
    with FakeOpenAIServer(images=False) as server:
        notes = preflight([spec(server, images="measurements")])
        assert any("does not report its context length" in n for n in notes)
        preflight([spec(server, "flip-box", "coral", "default", "all")])
        assert server.requests == []


def test_strict_mode_needs_the_strict_options_auto_only_notes_them() -> None:
    with FakeOpenAIServer(refuse={"json_schema"}, refuse_status=500) as server:
        with pytest.raises(CapabilityError, match="does not honour strict response_format json_schema .*HTTP 500.*"
                                                  "recovery's analyze, judge need it with --structured-output strict"):
            preflight([spec(server, mode="strict")])
        notes = preflight([spec(server)])
        assert any("recovery's analyze, judge will ask for JSON in text" in n for n in notes)


def test_a_context_too_small_for_the_prompts_stops_the_campaign() -> None:
    with FakeOpenAIServer() as server:
        with pytest.raises(CapabilityError, match=r"recovery's \w+ needs at least [\d,]+ tokens before its request "
                                                  r"data .* but the model's context is 1,024 \(reasoner.options"):
            preflight([spec(server, context_tokens=1024)])
        assert preflight([spec(server, context_tokens=200_000)]) == []


def test_preflight_can_be_turned_off_and_skips_offline_backends() -> None:
    with FakeOpenAIServer(images=False) as server:
        assert preflight([spec(server, preflight=False)]) == []
        offline = spec(server).model_copy(update={"reasoner": ReasonerSettings()})
        assert preflight([offline]) == [] and server.probes == []
