"""A small role for the protocol's tests: no simulator, no prompt beyond one file, an embedded answer
and a check, so every backend path can be exercised in milliseconds."""

from __future__ import annotations

from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role


class EchoRequest(StrictModel):
    text: str
    times: int = 1


class EchoReply(StrictModel):
    echo: str = Field(max_length=200)


def embedded_echo(request: EchoRequest) -> EchoReply:
    return EchoReply(echo=request.text * request.times)


def check_echo(reply: EchoReply, request: EchoRequest) -> EchoReply:
    if request.text not in reply.echo:
        raise BadReply(f"the echo must repeat {request.text!r}")
    return reply


ECHO = ROLES.get("test-echo") if "test-echo" in ROLES else ROLES.register(
    Role(name="test-echo", request=EchoRequest, reply=EchoReply, package="tests.reasoning", embedded=embedded_echo,
         check=check_echo, prompt="echo"))
