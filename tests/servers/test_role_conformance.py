"""Every reasoner role of every system through the `openai` backend against real server software.

The model is random, so model quality is not the point: each call must end in a reply that passes the
role's validation and checks, or in a recorded, clear ReasoningError (a failed repair round, an endpoint
error), never a crash, a hang or a reply the validators would refuse."""

from __future__ import annotations

import re
import time

import pytest

from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.reasoning.endpoint_options import OpenAIOptions
from kintsugi.reasoning.openai_backend import OpenAIReasoner
from kintsugi.reasoning.roles import ROLES, ask
from kintsugi.reasoning.transport import ContextTooLong, EndpointError, ImagesRefused
from kintsugi.testing.role_requests import REQUESTS, build, system_roles
from kintsugi.testing.servers import Server

ROLE_NAMES = sorted(REQUESTS)
system_roles()  # registers every role (imports the methods that ask them)
CALL_LIMIT_S = 250.0
"""No call outlives its transport bounds: 2 attempts x (1 + max_retries) x timeout_s, plus slack (a 30k-token
prompt on one thread of a loaded machine takes a minute)."""


def reasoner(server: Server, mode: str, images: str = "measurements", tokens: int = 160) -> RecordingReasoner:
    return RecordingReasoner(OpenAIReasoner(model="tiny", base_url=server.base_url, timeout_s=60, max_retries=1,
                                            structured_output=mode,
                                            options=OpenAIOptions(images=images, max_reply_tokens=tokens)))


def conform(rec: RecordingReasoner, role_name: str) -> str:
    """Ask once; assert the call ended in a checked reply or a clear recorded error; return which."""
    role, request = ROLES.get(role_name), build(role_name)
    start = time.monotonic()
    try:
        reply = ask(rec, role_name, request)
    except ReasoningError as exc:
        message = str(exc)
        assert message and "\n" not in message.strip() and len(message) < 4000, message
        last = rec.records[-1]
        assert last.role == role_name and last.reply is None and last.error and message in last.error
        if "gave no usable reply" in message:
            assert last.attempts == 2  # the repair round ran
        outcome = "error"
    else:
        assert isinstance(reply, role.reply)
        again = role.reply.model_validate(reply.model_dump())  # a reply the validators would refuse never passes
        if role.check is not None:
            role.check(again, request)
        assert rec.records[-1].error is None and rec.records[-1].reply is not None
        outcome = "reply"
    assert time.monotonic() - start < CALL_LIMIT_S
    assert rec.records[-1].tokens_in > 0 or rec.records[-1].error
    return outcome


def test_every_role_of_every_system_has_a_conformance_request() -> None:
    assert set(system_roles()) <= set(REQUESTS), "a registered role has no request in kintsugi/testing/role_requests.py"


@pytest.mark.parametrize("mode", ["strict", "auto", "text"])
@pytest.mark.parametrize("role_name", ROLE_NAMES)
def test_llama_server_every_role(llama_server: Server, role_name: str, mode: str) -> None:
    rec = reasoner(llama_server, mode)
    conform(rec, role_name)
    call = rec.records[-1]
    # llama-server honours strict json_schema and tool_choice="required": auto never falls back
    assert call.output_mode == ("text" if mode == "text" else "strict"), call.output_note
    assert call.images_sent == 0
    if image_fields(role_name):
        assert call.images_withheld > 0


def image_fields(role_name: str) -> bool:
    from kintsugi.reasoning.preflight import image_use

    return image_use(ROLES.get(role_name)) == "always"


def test_llama_server_plan_arrives_as_tool_calls(llama_server: Server) -> None:
    rec = reasoner(llama_server, "strict")
    conform(rec, "plan")
    call = rec.records[-1]
    assert call.output_mode == "strict"
    if call.error:
        assert "no tool call" not in call.error  # tool_choice="required" was honoured


def test_llama_server_refuses_images_with_one_clear_error(llama_server: Server) -> None:
    rec = reasoner(llama_server, "auto", images="send")
    start = time.monotonic()
    with pytest.raises(ImagesRefused, match="takes no images.*judge request sends camera images.*images=measurements"):
        ask(rec, "judge", build("judge"))
    assert time.monotonic() - start < 10  # not retried
    assert rec.records[-1].images_sent >= 1 and "ImagesRefused" in rec.records[-1].error


def test_a_request_longer_than_the_context_is_one_clear_error(llama_server_small: Server) -> None:
    rec = reasoner(llama_server_small, "text")
    with pytest.raises(ContextTooLong) as info:
        ask(rec, "formulate", build("formulate"))
    message = str(info.value)
    assert re.search(r"the request is [\d,]+ tokens against the model's 2,048-token context", message), message
    assert "system" in message and "chars" in message  # which part is large


@pytest.mark.parametrize("role_name", ROLE_NAMES)
def test_llama_cpp_python_auto_falls_back_to_text(llama_cpp_python: Server, role_name: str) -> None:
    rec = reasoner(llama_cpp_python, "auto")
    try:
        conform(rec, role_name)
    except EndpointError as exc:  # pragma: no cover - a failure message worth reading
        pytest.fail(f"auto mode ended in an endpoint error: {exc}")
    call = rec.records[-1]
    assert call.error is None or "EndpointError" not in call.error, call.error
    if ROLES.get(role_name).tools is None:  # strict json_schema is refused with a 500: auto switches to text
        assert call.output_mode == "text"
        assert call.output_note and "refused" in call.output_note and "HTTP 500" in call.output_note
    else:  # tool calls: honoured (the reply came as a tool call) or refused and asked for in text
        assert call.output_mode in ("strict", "text")
        assert call.output_mode == "strict" or (call.output_note and "tool" in call.output_note)


def test_llama_cpp_python_refusal_is_not_retried(llama_cpp_python: Server) -> None:
    before = llama_cpp_python.log.read_text(errors="replace").count("500 Internal Server Error")
    rec = reasoner(llama_cpp_python, "strict")
    with pytest.raises(EndpointError, match="refused strict structured output for judge .*HTTP 500"):
        ask(rec, "judge", build("judge"))
    after = llama_cpp_python.log.read_text(errors="replace").count("500 Internal Server Error")
    assert after - before == 1
