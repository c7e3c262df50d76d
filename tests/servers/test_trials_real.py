"""One short trial per system through the `openai` backend against llama.cpp's server, and a campaign that
the preflight stops before its first trial. The random model's replies mostly fail validation: the point
is that every call ends in a checked reply or a recorded, clear error, and the record counts every call."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.reasoning.preflight import CapabilityError, preflight
from kintsugi.testing.servers import Server

SYSTEMS = [("peg-insertion", "recovery", "square", "none"), ("pour-single", "agentchord", "default", "none"),
           ("flip-box", "coral", "default", "all")]


def spec(server: Server, task: str, method: str, variant: str, condition: str, **options: object) -> TrialSpec:
    return TrialSpec(task=task, method=method, variant=variant, condition=condition, seed=0, reasoner=ReasonerSettings(
        backend="openai", model="tiny", base_url=server.base_url, timeout_s=60, max_retries=1,
        options={"max_reply_tokens": 160, **options}))


@pytest.mark.slow
@pytest.mark.parametrize(("task", "method", "variant", "condition"), SYSTEMS)
def test_one_trial_per_system_with_measurements_instead_of_images(llama_server: Server, task: str, method: str,
                                                                  variant: str, condition: str) -> None:
    s = spec(llama_server, task, method, variant, condition, images="measurements")
    try:
        preflight([s])  # no image is sent; the context may still be too short for the largest first request
    except CapabilityError as exc:  # AgentChord's arranger asks more than the tiny model's context holds
        message = str(exc)
        assert "\n" not in message.strip() and "context" in message and "the request data is the largest" in message
    rec = run_trial(s)  # the trial runs anyway: each call ends in a checked reply or a recorded error
    assert rec.reasoning_calls >= 1 and rec.reasoning_calls == len(rec.transcript)
    assert rec.reasoning_errors == sum(1 for c in rec.transcript if c["error"])
    for call in rec.transcript:
        assert (call["reply"] is None) != (call["error"] is None), call
        assert call["backend"] == "openai" and call["images_sent"] == 0
        assert call["tokens_in"] > 0 or call["error"]  # an endpoint error may come before any token is counted
    if rec.error is not None:  # a recorded reasoning/endpoint error, never a crash
        assert "Traceback" not in rec.error and "Error" in rec.error.splitlines()[0], rec.error
    if task == "peg-insertion":
        assert rec.transcript[0]["images_withheld"] > 0


@pytest.mark.parametrize(("task", "method"), [("peg-insertion", "recovery"), ("pour-single", "agentchord")])
def test_a_campaign_on_a_text_only_server_stops_before_its_first_trial(llama_server: Server, tmp_path, task: str,
                                                                       method: str) -> None:  # noqa: ANN001
    from kintsugi.cli import app

    out = tmp_path / "campaign"
    result = CliRunner().invoke(app, ["bench", task, "--methods", method, "--trials", "1", "--workers", "1",
                                      "--reasoner", "openai", "--model", "tiny", "--base-url", llama_server.base_url,
                                      "--out", str(out)])
    assert result.exit_code == 2, result.output
    message = " ".join(result.output.split())
    assert "takes no images" in message and f"{method}'s" in message and "images=measurements" in message
    results = out / "results.jsonl"
    assert not results.exists() or not results.read_text().strip()


def test_the_preflight_reads_the_context_from_llama_server(llama_server_small: Server) -> None:
    from kintsugi.reasoning.preflight import CapabilityError

    s = spec(llama_server_small, "flip-box", "coral", "default", "all", images="measurements")
    with pytest.raises(CapabilityError, match=r"coral's \w+ .*2,048.*longer context") as info:
        preflight([s])
    assert "\n" not in str(info.value)
    assert json.dumps(llama_server_small.get("/props")["default_generation_settings"]["n_ctx"]) == "2048"
