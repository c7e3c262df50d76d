"""The scripted backend: replies from JSONL, from a trial record, from a function; checked like a model's."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from kintsugi.core.errors import ConfigError, ReasoningError
from kintsugi.core.record import ReasonerSettings, TrialRecord, TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.reasoning import make_reasoner
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask
from kintsugi.reasoning.scripted import ScriptedReasoner
from tests.reasoning.roles_fixtures import EchoReply, EchoRequest


def scripted(**options: object) -> RecordingReasoner:
    return RecordingReasoner(make_reasoner(ReasonerSettings(backend="scripted", options=options)))


def write_jsonl(path: Path, *items: object) -> str:
    path.write_text("".join(json.dumps(i) + "\n" for i in items) + "\n")
    return str(path)


def test_jsonl_replies_in_order_and_keyed_by_role(tmp_path: Path) -> None:
    if "test-echo-2" not in ROLES:
        ROLES.register(Role(name="test-echo-2", request=EchoRequest, reply=EchoReply, package="tests.reasoning",
                            prompt="echo"))
    path = write_jsonl(tmp_path / "r.jsonl", {"role": "test-echo-2", "reply": {"echo": "b1"}}, {"echo": "a1"},
                       {"echo": "a2"})
    rec = scripted(replies=path)
    assert ask(rec, "test-echo", EchoRequest(text="a")).echo == "a1"  # the keyed line is another role's
    assert ask(rec, "test-echo-2", EchoRequest(text="b")).echo == "b1"
    assert ask(rec, "test-echo", EchoRequest(text="a")).echo == "a2"
    assert [(c.role, c.backend, c.reply) for c in rec.records] == [
        ("test-echo", "scripted", {"echo": "a1"}), ("test-echo-2", "scripted", {"echo": "b1"}),
        ("test-echo", "scripted", {"echo": "a2"})]


def test_running_out_of_replies_is_a_recorded_reasoning_error(tmp_path: Path) -> None:
    rec = scripted(replies=write_jsonl(tmp_path / "r.jsonl", {"echo": "a"}))
    ask(rec, "test-echo", EchoRequest(text="a"))
    with pytest.raises(ReasoningError, match="ran out: no reply left for role 'test-echo' \\(call 2\\)"):
        ask(rec, "test-echo", EchoRequest(text="a"))
    assert rec.records[-1].reply is None and "ran out" in rec.records[-1].error and rec.errors == 1


def test_a_bad_reply_is_rejected_like_a_models(tmp_path: Path) -> None:
    path = write_jsonl(tmp_path / "r.jsonl", {"echoo": "a"}, {"echo": "zzz"}, {"role": "test-echo", "error": "down"})
    rec = scripted(replies=path)
    with pytest.raises(BadReply, match="does not match the schema: echo: Field required"):
        ask(rec, "test-echo", EchoRequest(text="a"))
    with pytest.raises(BadReply, match="must repeat 'a'"):  # the role's own check
        ask(rec, "test-echo", EchoRequest(text="a"))
    with pytest.raises(ReasoningError, match="scripted failure for test-echo: down"):
        ask(rec, "test-echo", EchoRequest(text="a"))
    assert [c.error.split(":")[0] for c in rec.records] == ["BadReply", "BadReply", "ReasoningError"]


def test_replies_from_a_function() -> None:
    asked = []

    def answer(role: str, request: EchoRequest) -> dict:
        asked.append(role)
        return {"echo": request.text.upper() + request.text}

    rec = RecordingReasoner(ScriptedReasoner(answer))
    assert ask(rec, "test-echo", EchoRequest(text="a")).echo == "Aa" and asked == ["test-echo"]


def test_replies_from_a_module_function_by_name() -> None:
    rec = scripted(function="tests.reasoning.test_scripted:shout")
    assert ask(rec, "test-echo", EchoRequest(text="a")).echo == "A!a"


def shout(role: str, request: EchoRequest) -> EchoReply:
    return EchoReply(echo=f"{request.text.upper()}!{request.text}")


def test_a_missing_or_broken_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read"):
        scripted(replies=str(tmp_path / "missing.jsonl"))
    (tmp_path / "bad.jsonl").write_text('{"echo": "a"}\nnot json\n')
    with pytest.raises(ConfigError, match=r"bad.jsonl:2: not valid JSON"):
        scripted(replies=str(tmp_path / "bad.jsonl"))
    with pytest.raises(ConfigError, match="set exactly one of replies"):
        scripted()


def test_a_peg_trial_replays_from_its_own_record(tmp_path: Path) -> None:
    """A recovery trial's transcript, replayed by the scripted backend, gives the same trial call for call."""
    spec = TrialSpec(task="peg-insertion", method="recovery", variant="square", condition="all", seed=1)
    first = run_trial(spec)
    assert first.error is None and {"judge", "analyze", "plan"} <= {c["role"] for c in first.transcript}
    path = tmp_path / "first.json"
    path.write_text(first.model_dump_json())
    again = run_trial(spec.model_copy(update={"reasoner": ReasonerSettings(
        backend="scripted", options={"replies": str(path)})}))
    assert again.error is None and again.success == first.success
    assert [(c["role"], c["reply"]) for c in again.transcript] == [(c["role"], c["reply"]) for c in first.transcript]
    assert {c["backend"] for c in again.transcript} == {"scripted"}
    assert TrialRecord.model_validate_json(path.read_text()).without_timings()["skills"] == again.without_timings()["skills"]
