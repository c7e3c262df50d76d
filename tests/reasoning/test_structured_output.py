"""Strict / text / auto structured output against a fake server that refuses or ignores the strict options."""

from __future__ import annotations

import json

import pytest
from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError, ReasoningError
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.openai_backend import EndpointError, OpenAIReasoner
from kintsugi.reasoning.roles import ask
from kintsugi.methods.recovery.types import JudgeReply
from tests.fake_openai_server import FakeOpenAIServer, content, http_error, tool_calls
from kintsugi.testing.peg_requests import GOOD_ANALYSIS, analyze_request, judge_request, plan_request

STRICT_KEYS = ("response_format", "tools", "tool_choice")
JUDGE_OK = {"success": True, "explanation": "peg inside, like the goal image"}
PLAN_OK = {"steps": [{"skill": "align", "goal": {"y": 14.0}}, {"skill": "insert", "goal": {"z": -20.0}}]}


def make(server: FakeOpenAIServer, mode: str = "auto") -> OpenAIReasoner:
    return OpenAIReasoner(model="small-local", base_url=server.base_url, api_key_env="KINTSUGI_TEST_NO_SUCH_KEY",
                          timeout_s=5, max_retries=0, structured_output=mode)


def user_text(body: dict) -> str:
    """Everything the last user message says, text parts joined."""
    content_ = [m for m in body["messages"] if m["role"] == "user"][-1]["content"]
    return content_ if isinstance(content_, str) else "\n".join(p["text"] for p in content_ if p["type"] == "text")


def strict_keys(body: dict) -> set[str]:
    return {k for k in STRICT_KEYS if k in body}


@pytest.mark.parametrize("status", [400, 422])
def test_auto_falls_back_once_per_option_and_records_it(status: int) -> None:
    with FakeOpenAIServer(refuse={"json_schema", "tool_choice"}, refuse_status=status) as server:
        server.push(content(JUDGE_OK), content(GOOD_ANALYSIS.model_dump(mode="json")), content(PLAN_OK),
                    content(JUDGE_OK), content(PLAN_OK))
        rec = RecordingReasoner(make(server))
        assert ask(rec, "judge", judge_request()) == JudgeReply(**JUDGE_OK)
        assert ask(rec, "analyze", analyze_request()) == GOOD_ANALYSIS
        assert [(s.skill, s.goal) for s in ask(rec, "plan", plan_request()).steps] == [("align", {"y": 14.0}),
                                                                              ("insert", {"z": -20.0})]
        ask(rec, "judge", judge_request())
        ask(rec, "plan", plan_request())
        # each option was refused once; every later request went straight to text mode
        assert server.refused == 2 and len(server.requests) == 7
        sent = [strict_keys(b) for b in server.requests]
        assert sent == [{"response_format"}, set(), set(), {"tools", "tool_choice"}, set(), set(), set()]
        assert "# Answer format" in user_text(server.requests[1]) and '"explanation"' in user_text(server.requests[1])
        assert [r.output_mode for r in rec.records] == ["text"] * 5
        notes = [r.output_note for r in rec.records]
        assert notes[0] and "response_format json_schema" in notes[0] and f"HTTP {status}" in notes[0]
        assert notes[2] and 'tool_choice="required"' in notes[2] and "refused" in notes[2]
        assert notes[1] is notes[3] is notes[4] is None
        assert all(r.attempts == 1 and r.error is None for r in rec.records)


def test_auto_keeps_strict_for_the_option_the_server_accepts() -> None:
    with FakeOpenAIServer(refuse={"tool_choice"}) as server:
        server.push(content(PLAN_OK), content(JUDGE_OK))
        rec = RecordingReasoner(make(server))
        ask(rec, "plan", plan_request())
        ask(rec, "judge", judge_request())
        assert [strict_keys(b) for b in server.requests] == [{"tools", "tool_choice"}, set(), {"response_format"}]
        assert [r.output_mode for r in rec.records] == ["text", "strict"]


def test_strict_mode_surfaces_a_clear_error_and_does_not_retry() -> None:
    with FakeOpenAIServer(refuse={"json_schema"}) as server:
        rec = RecordingReasoner(make(server, "strict"))
        with pytest.raises(EndpointError, match="refused strict structured output for judge .*HTTP 400.*"
                                                "json_schema.*--structured-output auto or text"):
            ask(rec, "judge", judge_request())
        assert len(server.requests) == 1 and rec.errors == 1 and "EndpointError" in rec.records[0].error


def test_text_mode_never_sends_strict_options() -> None:
    with FakeOpenAIServer(refuse={"json_schema", "tool_choice"}) as server:
        server.push(content(JUDGE_OK), content(GOOD_ANALYSIS.model_dump(mode="json")),
                    content(json.dumps(PLAN_OK)), tool_calls(("grasp", {"y": 1})), content(PLAN_OK))
        rec = RecordingReasoner(make(server, "text"))
        ask(rec, "judge", judge_request())
        ask(rec, "analyze", analyze_request())
        ask(rec, "plan", plan_request())
        ask(rec, "plan", plan_request())  # a stray tool call is repaired like any bad reply
        assert server.refused == 0 and all(not strict_keys(b) for b in server.requests)
        plan_prompt = user_text(server.requests[2])
        assert "Do not call functions" in plan_prompt and '"steps"' in plan_prompt
        assert "- insert(z: absolute goal z in mm; current goal -20)" in plan_prompt
        assert [r.output_mode for r in rec.records] == ["text"] * 4 and rec.records[3].attempts == 2
        # images stay attached in text mode, the format comes after them
        parts = server.requests[0]["messages"][1]["content"]
        assert [p["type"] for p in parts].count("image_url") == 2 and "# Answer format" in parts[-1]["text"]


@pytest.mark.parametrize("reply", [
    "```json\n" + json.dumps(JUDGE_OK, indent=2) + "\n```",
    "Looking at {the images}, here is my verdict:\n" + json.dumps(JUDGE_OK) + "\nI hope this helps.",
    '{"success": true, "explanation": "peg inside, like the goal image",}',
    "{'success': True, 'explanation': 'peg inside, like the goal image'}",
])
def test_text_mode_parses_what_small_models_write(reply: str) -> None:
    with FakeOpenAIServer() as server:
        server.push(content(reply))
        r = make(server, "text")
        assert ask(r, "judge", judge_request()) == JudgeReply(**JUDGE_OK) and r.last_stats.attempts == 1


def test_garbage_gets_one_repair_round_then_a_recorded_reasoning_error() -> None:
    with FakeOpenAIServer(refuse={"json_schema"}) as server:
        server.push(content("The peg looks fine to me."), content(JUDGE_OK),
                    content("Still no JSON, sorry."), content('{"success": "probably"}'))
        rec = RecordingReasoner(make(server))
        assert ask(rec, "judge", judge_request()).success and rec.records[0].attempts == 2
        repair = server.requests[2]["messages"][-1]["content"]
        assert "no JSON object" in repair and "Answer again" in repair
        with pytest.raises(ReasoningError, match="no usable reply in 2 attempts"):
            ask(rec, "judge", judge_request())
        failed = rec.records[1]
        assert failed.reply is None and failed.attempts == 2 and failed.output_mode == "text"
        assert "ReasoningError" in failed.error and "does not match the schema" in failed.error
        assert len(server.requests) == 5 and server.refused == 1


def test_auto_detects_a_server_that_ignores_the_strict_options() -> None:
    with FakeOpenAIServer() as server:
        server.push(content("It worked, the peg is in."), content(JUDGE_OK),  # response_format ignored
                    content(PLAN_OK),  # tool_choice="required" ignored: JSON content, no tool call
                    content(JUDGE_OK), content(PLAN_OK))
        rec = RecordingReasoner(make(server))
        ask(rec, "judge", judge_request())
        ask(rec, "plan", plan_request())
        ask(rec, "judge", judge_request())
        ask(rec, "plan", plan_request())
        sent = [strict_keys(b) for b in server.requests]
        assert sent == [{"response_format"}, set(), {"tools", "tool_choice"}, set(), set()]
        # the repair turn after an ignored option carries the format the prompt did not have
        assert "# Answer format" in server.requests[1]["messages"][-1]["content"]
        assert [r.output_mode for r in rec.records] == ["text", "strict", "text", "text"]
        assert "ignored" in rec.records[0].output_note and "ignored" in rec.records[1].output_note
        assert rec.records[0].attempts == 2 and rec.records[1].attempts == 1


def test_strict_mode_ignored_options_are_repaired_without_switching() -> None:
    with FakeOpenAIServer() as server:
        server.push(content("It worked."), content(JUDGE_OK), content(JUDGE_OK))
        r = make(server, "strict")
        ask(r, "judge", judge_request())
        ask(r, "judge", judge_request())
        assert all(strict_keys(b) == {"response_format"} for b in server.requests)


def test_unrelated_http_400_is_not_a_fallback() -> None:
    with FakeOpenAIServer() as server:
        server.push(http_error(400, retry_after_s=None))
        r = make(server)
        with pytest.raises(EndpointError, match="HTTP 400"):
            ask(r, "judge", judge_request())
        assert r.structured.text_only == {}


class PriorsReply(StrictModel):
    """A role B or C might add: not known to the backend at all."""

    mass_kg: float = Field(gt=0)
    friction: float = Field(ge=0, le=2)


@pytest.mark.parametrize("mode", ["auto", "text"])
def test_any_reply_model_goes_through_the_same_path(mode: str) -> None:
    with FakeOpenAIServer(refuse={"json_schema"}) as server:
        server.push(content({"mass_kg": -1, "friction": 0.4}), content("```\n{'mass_kg': 0.35, 'friction': 0.4,}\n```"))
        r = make(server, mode)
        messages = [{"role": "system", "content": "You estimate physics."},
                    {"role": "user", "content": "Estimate the box's mass and friction."}]
        assert r.structured.ask("priors", messages, PriorsReply) == PriorsReply(mass_kg=0.35, friction=0.4)
        assert "mass_kg" in server.requests[-1]["messages"][-1]["content"]  # the error was quoted back
        assert '"exclusiveMinimum": 0' in user_text(server.requests[-2])  # the schema was in the prompt
        assert r.last_stats.output_mode == "text" and r.last_stats.attempts == 2


def test_bad_mode_is_a_config_error(fake_openai: FakeOpenAIServer) -> None:
    with pytest.raises(ConfigError, match="structured_output .*auto, strict, text"):
        make(fake_openai, "json")


from tests.fake_openai_server import fake_openai  # noqa: E402,F401  (fixture)


def test_cli_structured_output_option_reaches_the_backend_and_the_record(tmp_path) -> None:  # noqa: ANN001
    from typer.testing import CliRunner

    from kintsugi.cli import app
    from kintsugi.core.record import TrialRecord

    analysis = {"what_happened": "fit judged failed", "why": "scripted", "how_to_recover": "retry fit",
                "restart_from": "fit", "motions": [{"skill": "fit", "axis": "y", "delta": 0.0}]}
    plan = {"steps": [{"skill": "fit", "goal": {"y": 1.5}}, {"skill": "align", "goal": {"y": -1.0}},
                      {"skill": "insert", "goal": {"z": 115.0}}]}
    args = ["run", "peg-insertion", "--method", "recovery", "--shape", "square", "--reasoner", "openai",
            "--model", "scripted"]
    with FakeOpenAIServer(refuse={"json_schema", "tool_choice"}) as server:
        server.push(content({"success": False, "explanation": "tip not in the hole"}), content(analysis),
                    content(f"Here is the plan:\n```json\n{json.dumps(plan)}\n```"),
                    *[content({"success": True, "explanation": f"{s} ok"}) for s in ("fit", "align", "insert")])
        out = tmp_path / "auto.json"
        result = CliRunner().invoke(app, [*args, "--base-url", server.base_url, "--record", str(out)])
        assert result.exit_code == 0, result.output
        rec = TrialRecord.model_validate_json(out.read_text())
        assert rec.success and [c["output_mode"] for c in rec.transcript] == ["text"] * 6
        assert server.refused == 2 and [bool(c["output_note"]) for c in rec.transcript] == [1, 0, 1, 0, 0, 0]

    with FakeOpenAIServer(refuse={"json_schema"}) as server:
        out = tmp_path / "strict.json"
        result = CliRunner().invoke(app, [*args, "--base-url", server.base_url, "--record", str(out),
                                          "--structured-output", "strict"])
        # the preflight stops the run before the trial, in one line naming the option and the roles
        assert result.exit_code == 2 and not out.exists()
        assert "does not honour strict response_format json_schema" in result.output
        assert "recovery's analyze, judge need it with --structured-output strict" in result.output
        assert len(server.requests) == 0 and server.probes

    result = CliRunner().invoke(app, [*args, "--structured-output", "json"])
    assert result.exit_code == 2 and "json" in result.output
