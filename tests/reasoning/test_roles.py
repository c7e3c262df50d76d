"""The role registry and `ask`: one protocol for every role of every system, recorded in one transcript."""

from __future__ import annotations

import subprocess
import sys

import pytest

from kintsugi.core.errors import ReasoningError, UnknownNameError
from kintsugi.core.record import ReasonerSettings
from kintsugi.reasoning import make_reasoner
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.embedded import EmbeddedReasoner
from kintsugi.reasoning.roles import ROLES, Role, ask
from tests.fake_openai_server import fake_openai  # noqa: F401 - fixture
from tests.reasoning.roles_fixtures import ECHO, EchoReply, EchoRequest


def test_an_unknown_role_lists_the_known_ones() -> None:
    import kintsugi.methods.agentchord.verifier  # noqa: F401 - registers verify
    import kintsugi.methods.coral.priors  # noqa: F401 - registers priors
    import kintsugi.methods.recovery.roles  # noqa: F401 - registers judge, analyze, plan

    with pytest.raises(UnknownNameError, match=r"unknown role 'jugde'; known: .*judge.*priors.*verify"):
        ask(EmbeddedReasoner(), "jugde", EchoRequest(text="x"))


def test_every_system_registers_its_roles_beside_its_method() -> None:
    import kintsugi.methods.agentchord.arranger  # noqa: F401
    import kintsugi.methods.agentchord.composer  # noqa: F401
    import kintsugi.methods.agentchord.verifier  # noqa: F401
    import kintsugi.methods.coral.adapt  # noqa: F401
    import kintsugi.methods.coral.formulate  # noqa: F401
    import kintsugi.methods.coral.priors  # noqa: F401
    import kintsugi.methods.recovery.roles  # noqa: F401

    owners = {"judge": "recovery", "analyze": "recovery", "plan": "recovery", "composer": "agentchord",
              "arranger": "agentchord", "verify": "agentchord", "priors": "coral", "formulate": "coral",
              "adapt": "coral"}
    for name, method in owners.items():
        role = ROLES.get(name)
        assert role.package == f"kintsugi.methods.{method}" and role.embedded is not None
        assert role.prompt_path == f"kintsugi/methods/{method}/prompts/{name}.md"
        assert role.prompt_text().strip() and role.system_text().strip()  # shipped as package data


def test_ask_records_the_call_under_the_role_name() -> None:
    rec = RecordingReasoner(make_reasoner(ReasonerSettings()))
    assert ask(rec, "test-echo", EchoRequest(text="ab", times=2)) == EchoReply(echo="abab")
    (call,) = rec.records
    assert (call.role, call.backend, call.request, call.reply) == ("test-echo", "embedded",
                                                                   {"text": "ab", "times": 2}, {"echo": "abab"})


def test_the_roles_check_and_the_callers_run_on_embedded_replies_too() -> None:
    seen = []
    reply = ask(EmbeddedReasoner(), "test-echo", EchoRequest(text="a"), check=lambda r: seen.append(r) or r)
    assert seen == [reply]
    with pytest.raises(ReasoningError, match="must repeat"):
        ask(EmbeddedReasoner(), "test-echo", EchoRequest(text="a", times=0))  # "" fails the role's check


def test_a_request_of_the_wrong_type_is_refused() -> None:
    import kintsugi.methods.recovery.roles  # noqa: F401

    with pytest.raises(TypeError, match="judge.*JudgeRequest, not a EchoRequest"):
        ask(EmbeddedReasoner(), "judge", EchoRequest(text="a"))


def test_a_role_without_embedded_answer_is_a_recorded_reasoning_error() -> None:
    if "test-model-only" not in ROLES:
        ROLES.register(Role(name="test-model-only", request=EchoRequest, reply=EchoReply, package="tests.reasoning",
                            prompt="echo"))
    rec = RecordingReasoner(EmbeddedReasoner())
    with pytest.raises(ReasoningError, match="no embedded answer"):
        ask(rec, "test-model-only", EchoRequest(text="a"))
    assert rec.records[0].role == "test-model-only" and "no embedded answer" in rec.records[0].error


def test_a_backend_answering_with_the_wrong_type_is_a_reasoning_error() -> None:
    class Wrong:
        name = "wrong"

        def answer(self, role, request, check=None):  # noqa: ANN001, ANN201
            return EchoRequest(text="not a reply")

    with pytest.raises(ReasoningError, match="answered role 'test-echo' with a EchoRequest, not a EchoReply"):
        ask(Wrong(), ECHO.name, EchoRequest(text="a"))


def test_the_embedded_backend_never_imports_the_model_sdk() -> None:
    code = ("import sys\n"
            "from kintsugi.core.record import ReasonerSettings, TrialSpec\n"
            "from kintsugi.core.runner import run_trial\n"
            "from kintsugi.reasoning import REASONERS, load_builtin_backends\n"
            "load_builtin_backends(); assert 'openai' in REASONERS\n"
            "r = run_trial(TrialSpec(task='peg-insertion', method='recovery', variant='square', condition='none', "
            "seed=0))\n"
            "assert r.error is None and r.reasoning_calls > 0, r.error\n"
            "bad = [m for m in sys.modules if m == 'openai' or m.startswith(('openai.', 'kintsugi.reasoning.openai', "
            "'kintsugi.reasoning.structured'))]\n"
            "print(bad); sys.exit(1 if bad else 0)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr


def test_reasoning_perception_and_worlds_import_no_method() -> None:
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[2] / "kintsugi"
    for layer in ("reasoning", "perception", "worlds"):
        for path in (root / layer).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            assert "import kintsugi.methods" not in text and "from kintsugi.methods" not in text, path


def test_a_new_role_reaches_a_model_with_its_own_prompts_and_check(fake_openai) -> None:  # noqa: ANN001
    from kintsugi.reasoning.openai_backend import OpenAIReasoner
    from tests.fake_openai_server import content

    fake_openai.push(content({"echo": "zz"}), content({"echo": "aa"}))  # the first fails the role's check
    model = RecordingReasoner(OpenAIReasoner(model="m", base_url=fake_openai.base_url, timeout_s=5, max_retries=0,
                                             api_key_env="KINTSUGI_TEST_NO_SUCH_KEY"))
    assert ask(model, "test-echo", EchoRequest(text="a", times=2)) == EchoReply(echo="aa")
    first, repair = fake_openai.requests
    assert first["messages"][0] == {"role": "system", "content": ECHO.system_text()}
    assert first["messages"][1]["content"].startswith(ECHO.prompt_text())
    assert "must repeat 'a'" in repair["messages"][-1]["content"]
    assert model.records[0].attempts == 2 and model.records[0].backend == "openai"
