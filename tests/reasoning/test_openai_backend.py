"""OpenAIReasoner against a local fake OpenAI server: happy paths, retries, repair, limits."""

from __future__ import annotations

import base64
import time

import pytest

from tests.fake_openai_server import FakeOpenAIServer, content, fake_openai, hang, http_error, refusal, tool_calls  # noqa: F401
from kintsugi.core.errors import ConfigError, KintsugiError, ReasoningError, UnknownNameError
from kintsugi.reasoning import REASONERS, make_reasoner
from kintsugi.reasoning.base import Reasoner, RecordingReasoner
from kintsugi.reasoning.openai_backend import EndpointError, OpenAIReasoner, strict_schema
from kintsugi.reasoning.roles import ask, read_prompt
from kintsugi.methods.recovery import roles  # noqa: F401 - registers judge, analyze and plan
from kintsugi.methods.recovery.types import AnalyzeReply, JudgeReply, PlanReply
from kintsugi.perception.types import Pose
from kintsugi.methods.recovery.validation import validate_plan
from kintsugi.core.record import ReasonerSettings
from kintsugi.testing.peg_requests import GOAL_PNG, GOOD_ANALYSIS, TERMINAL_PNG, analyze_request, judge_request, plan_request


def load_prompt(name: str) -> str:
    """The peg recovery's prompt file prompts/<name>.md (beside its roles)."""
    return read_prompt("kintsugi.methods.recovery", f"prompts/{name}.md")


def reasoner(server: FakeOpenAIServer, timeout_s: float = 5.0, max_retries: int = 2) -> OpenAIReasoner:
    return OpenAIReasoner(model="fake-vlm", base_url=server.base_url, api_key_env="KINTSUGI_TEST_NO_SUCH_KEY",
                          timeout_s=timeout_s, max_retries=max_retries)


# --- happy paths -------------------------------------------------------------

def test_judge_sends_images_schema_and_prompts(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content({"success": True, "explanation": "peg is inside like in the goal image"}, usage=(321, 17)))
    r = reasoner(fake_openai)
    reply = ask(r, "judge", judge_request())
    assert reply == JudgeReply(success=True, explanation="peg is inside like in the goal image")
    assert (r.last_stats.tokens_in, r.last_stats.tokens_out, r.last_stats.attempts) == (321, 17, 1)

    (body,) = fake_openai.requests
    assert body["model"] == "fake-vlm"
    assert body["messages"][0] == {"role": "system", "content": load_prompt("system")}
    parts = body["messages"][1]["content"]
    assert parts[0]["type"] == "text" and load_prompt("judge") in parts[0]["text"]
    assert "<image 1, attached below>" in parts[0]["text"] and "<image 2, attached below>" in parts[0]["text"]
    urls = [p["image_url"]["url"] for p in parts if p["type"] == "image_url"]
    prefix = "data:image/png;base64,"
    assert all(u.startswith(prefix) for u in urls)
    assert [base64.b64decode(u[len(prefix):]) for u in urls] == [TERMINAL_PNG, GOAL_PNG]
    labels = [p["text"] for p in parts[1:] if p["type"] == "text"]
    assert "terminal" in labels[0] and "goal image" in labels[1]
    fmt = body["response_format"]
    assert fmt["type"] == "json_schema" and fmt["json_schema"]["name"] == "JudgeReply"
    assert set(fmt["json_schema"]["schema"]["required"]) == {"success", "explanation"}
    assert fake_openai.headers[0]["authorization"] == "Bearer sk-local-no-key"


def test_analyze_happy_path(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content(GOOD_ANALYSIS.model_dump(mode="json")))
    assert ask(reasoner(fake_openai), "analyze", analyze_request()) == GOOD_ANALYSIS
    body = fake_openai.requests[0]
    assert body["response_format"]["json_schema"]["name"] == "AnalyzeReply"
    images = [p for p in body["messages"][1]["content"] if p["type"] == "image_url"]
    assert len(images) == 1


def test_plan_from_ordered_tool_calls(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(tool_calls(("fit", {"y": 11.0}), ("align", {"y": 14.0}), ("insert", {"z": -20.0})))
    reply = ask(reasoner(fake_openai), "plan", plan_request())
    assert [(s.skill, s.goal) for s in reply.steps] == [("fit", {"y": 11.0}), ("align", {"y": 14.0}),
                                                       ("insert", {"z": -20.0})]
    body = fake_openai.requests[0]
    assert body["tool_choice"] == "required"
    tools = {t["function"]["name"]: t["function"]["parameters"] for t in body["tools"]}
    assert set(tools) == {"fit", "align", "insert"}
    assert tools["insert"]["required"] == ["z"] and set(tools["fit"]["properties"]) == {"y"}
    assert isinstance(body["messages"][1]["content"], str)  # no images for the plan role


def test_plan_accepts_json_content_instead_of_tool_calls(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content("```json\n" + '{"steps": [{"skill": "align", "goal": {"y": 13}}, '
                             '{"skill": "insert", "goal": {}}]}' + "\n```"))
    reply = ask(reasoner(fake_openai), "plan", plan_request())
    assert [s.skill for s in reply.steps] == ["align", "insert"]


# --- transport: retries and timeouts ------------------------------------------

@pytest.mark.parametrize("status", [429, 500])
def test_sdk_retries_transient_http_errors(fake_openai: FakeOpenAIServer, status: int) -> None:
    fake_openai.push(http_error(status), content({"success": False, "explanation": "peg on rim"}))
    r = reasoner(fake_openai)
    assert ask(r, "judge", judge_request()).success is False
    assert len(fake_openai.requests) == 2
    assert r.last_stats.attempts == 1  # transport retries are not repair attempts


def test_persistent_http_error_becomes_endpoint_error(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(http_error(503), http_error(503))
    with pytest.raises(EndpointError, match="HTTP 503"):
        ask(reasoner(fake_openai, max_retries=1), "judge", judge_request())
    assert len(fake_openai.requests) == 2


def test_hang_times_out_is_retried_then_fails_cleanly(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(hang(3.0), hang(3.0))
    start = time.perf_counter()
    with pytest.raises(EndpointError, match="within 0.5 s"):
        ask(reasoner(fake_openai, timeout_s=0.5, max_retries=1), "judge", judge_request())
    elapsed = time.perf_counter() - start
    assert len(fake_openai.requests) == 2
    assert 1.0 <= elapsed < 2.9  # two 0.5 s timeouts plus one backoff, not the 3 s hang


def test_hang_then_good_reply_recovers(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(hang(3.0), content({"success": True, "explanation": "ok"}))
    assert ask(reasoner(fake_openai, timeout_s=0.5, max_retries=1), "judge", judge_request()).success


# --- repair loop ------------------------------------------------------------

def test_malformed_json_is_repaired_once(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content('{"success": tru', usage=(50, 5)), content({"success": True, "explanation": "ok"},
                                                                        usage=(60, 6)))
    r = reasoner(fake_openai)
    assert ask(r, "judge", judge_request()).success is True
    assert (r.last_stats.attempts, r.last_stats.tokens_in, r.last_stats.tokens_out) == (2, 110, 11)
    second = fake_openai.requests[1]["messages"]
    assert second[2] == {"role": "assistant", "content": '{"success": tru'}
    assert second[3]["role"] == "user" and "not valid JSON" in second[3]["content"]


def test_malformed_twice_raises(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content("I think it worked!"), content("still not json"))
    with pytest.raises(ReasoningError, match="no usable reply in 2 attempts") as err:
        ask(reasoner(fake_openai), "judge", judge_request())
    assert len(fake_openai.requests) == 2
    assert "check the prompt in kintsugi/methods/recovery/prompts/judge.md" in str(err.value)


def test_refusal_is_reported_and_repaired(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(refusal("I cannot help with that"), content({"success": True, "explanation": "ok"}))
    assert ask(reasoner(fake_openai), "judge", judge_request()).success
    assert "refused (I cannot help with that)" in fake_openai.requests[1]["messages"][-1]["content"]


def test_wrong_types_are_quoted_back(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content({"success": "maybe", "explanation": ["x"]}),
                     content({"success": False, "explanation": "fixed"}))
    assert ask(reasoner(fake_openai), "judge", judge_request()).explanation == "fixed"
    repair = fake_openai.requests[1]["messages"][-1]["content"]
    assert "success" in repair and "explanation" in repair and "schema" in repair


def test_analysis_with_unowned_axis_is_repaired(fake_openai: FakeOpenAIServer) -> None:
    bad = GOOD_ANALYSIS.model_dump(mode="json") | {"motions": [{"skill": "fit", "axis": "z", "delta": 1.0}]}
    fake_openai.push(content(bad), content(GOOD_ANALYSIS.model_dump(mode="json")))
    r = reasoner(fake_openai)
    assert ask(r, "analyze", analyze_request()) == GOOD_ANALYSIS and r.last_stats.attempts == 2
    assert "does not control axis 'z'" in fake_openai.requests[1]["messages"][-1]["content"]


def test_unknown_skill_tool_call_is_repaired(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(tool_calls(("grasp", {"y": 1.0}), ("insert", {"z": -20.0})),
                     tool_calls(("align", {"y": 13.0}), ("insert", {"z": -20.0})))
    r = reasoner(fake_openai)
    reply = ask(r, "plan", plan_request())
    assert [s.skill for s in reply.steps] == ["align", "insert"] and r.last_stats.attempts == 2
    msgs = fake_openai.requests[1]["messages"]
    assistant, tool_msgs, user = msgs[2], msgs[3:5], msgs[5]
    ids = [c["id"] for c in assistant["tool_calls"]]
    assert [m["tool_call_id"] for m in tool_msgs] == ids and all(m["role"] == "tool" for m in tool_msgs)
    assert "unknown tool 'grasp'" in user["content"]


def test_plan_with_wrong_axis_then_still_wrong_raises(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(tool_calls(("insert", {"y": 3.0})), tool_calls(("insert", {"z": "deep"})))
    with pytest.raises(ReasoningError):
        ask(reasoner(fake_openai), "plan", plan_request())


def test_huge_goal_jump_is_accepted_then_clamped(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(tool_calls(("align", {"y": 500.0}), ("insert", {"z": -20.0})))
    request = plan_request()
    reply = ask(reasoner(fake_openai), "plan", request)
    assert reply.steps[0].goal == {"y": 500.0}  # the backend does not clamp ...
    plan = validate_plan(reply, request)  # ... the caller does
    assert plan.steps[0].goal == {"y": 17.0}  # current 12 + max step 5
    assert plan.steps[0].pose == Pose(y=17.0, z=5.0)
    assert any("500 -> 17" in n for n in plan.notes)
    assert len(fake_openai.requests) == 1


# --- accounting, registry, configuration ------------------------------------

def test_recording_reasoner_keeps_transcript(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(content({"success": True, "explanation": "ok"}, usage=(400, 30)),
                     content("nope"), content("nope again"))
    rec = RecordingReasoner(reasoner(fake_openai))
    assert isinstance(rec.inner, Reasoner)
    ask(rec, "judge", judge_request())
    with pytest.raises(ReasoningError):
        ask(rec, "judge", judge_request())
    ok, failed = rec.records
    assert (ok.role, ok.backend, ok.tokens_in, ok.tokens_out, ok.attempts) == ("judge", "openai", 400, 30, 1)
    assert ok.reply == {"success": True, "explanation": "ok"} and ok.error is None and ok.latency_s > 0
    assert ok.request["outcome"]["image_png"] == f"<png {len(TERMINAL_PNG)} bytes>"
    assert ok.request["goal_image_png"] == f"<png {len(GOAL_PNG)} bytes>"
    assert failed.reply is None and "ReasoningError" in failed.error and failed.attempts == 2
    assert failed.tokens_in == 200
    assert rec.errors == 1 and rec.total_latency_s >= ok.latency_s


def test_recording_reasoner_records_endpoint_errors(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(http_error(400, retry_after_s=None))
    rec = RecordingReasoner(reasoner(fake_openai))
    with pytest.raises(EndpointError):
        ask(rec, "plan", plan_request())
    assert rec.records[0].role == "plan" and "HTTP 400" in rec.records[0].error


def test_make_reasoner_builds_openai_backend(fake_openai: FakeOpenAIServer) -> None:
    settings = ReasonerSettings(backend="openai", model="m", base_url=fake_openai.base_url,
                                api_key_env="KINTSUGI_TEST_NO_SUCH_KEY", timeout_s=2, max_retries=0)
    r = make_reasoner(settings)
    assert isinstance(r, OpenAIReasoner) and r.name == "openai" and "openai" in REASONERS
    with pytest.raises(UnknownNameError, match="known: .*openai"):
        make_reasoner(ReasonerSettings(backend="no-such-backend"))


def test_api_key_rules(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("KINTSUGI_TEST_KEY", raising=False)
    with pytest.raises(ConfigError, match="export KINTSUGI_TEST_KEY"):
        OpenAIReasoner(model="gpt-4o", api_key_env="KINTSUGI_TEST_KEY")
    with pytest.raises(ConfigError, match="reasoner.model"):
        OpenAIReasoner(base_url="http://127.0.0.1:9/v1", api_key_env="KINTSUGI_TEST_KEY")
    monkeypatch.setenv("KINTSUGI_TEST_KEY", "sk-test")
    r = OpenAIReasoner(api_key_env="KINTSUGI_TEST_KEY")  # constructing makes no request
    assert r.model == "gpt-4o" and r.client.api_key == "sk-test"
    assert issubclass(ConfigError, KintsugiError)


def test_unreachable_server_is_endpoint_error() -> None:
    with FakeOpenAIServer() as server:
        url = server.base_url
    r = OpenAIReasoner(model="m", base_url=url, api_key_env="KINTSUGI_TEST_NO_SUCH_KEY", timeout_s=1, max_retries=0)
    with pytest.raises(EndpointError, match="cannot reach"):
        ask(r, "judge", judge_request())


def test_strict_schema_requires_every_field() -> None:
    schema = strict_schema(AnalyzeReply)
    assert schema["additionalProperties"] is False
    assert set(schema["required"]) == set(AnalyzeReply.model_fields)
    motion = schema["$defs"]["RelativeMotion"]
    assert motion["required"] == ["skill", "axis", "delta"] and motion["additionalProperties"] is False
    assert "default" not in str(schema) and "maxLength" not in str(schema)


def test_prompts_state_units_and_stage_conventions() -> None:
    assert "millimetres" in load_prompt("system") and "p_gy was too small" in load_prompt("system")
    assert "relative to the current goal" in load_prompt("analyze")
    assert "absolute" in load_prompt("plan") and "max_step_mm" in load_prompt("plan")
    assert "goal image" in load_prompt("judge")


def test_plan_reply_type_is_unclamped_plan_reply(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(tool_calls(("insert", {"z": -21.0})))
    assert isinstance(ask(reasoner(fake_openai), "plan", plan_request()), PlanReply)
