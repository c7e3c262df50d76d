"""Roles beyond the peg recovery's judge/analyze/plan, on the same backends and transcript.

A role is a request type, a reply type, a prompt file `prompts/<role>.md`, and an embedded answer
(a plain function of the request). `ask_role` sends it to whatever backend the trial built: the
embedded backend answers with that function; a model endpoint (anything with `ask`, i.e. the
openai backend) gets the prompt and the request, with strict/text output, the repair round and
token accounting. When the reasoner records (RecordingReasoner), the call lands in the transcript
under the role's name. `check` runs on every reply, embedded or not: it may raise BadReply (an
endpoint is then asked once to repair) or return a corrected reply.
"""

from __future__ import annotations

from typing import Any, Callable, TypeVar

from pydantic import BaseModel

from kintsugi.core.errors import ReasoningError

Req = TypeVar("Req", bound=BaseModel)
Rep = TypeVar("Rep", bound=BaseModel)


def ask_role(reasoner: Any, role: str, request: Req, reply: type[Rep], embedded: Callable[[Req], Rep],
             check: Callable[[Rep], Rep] | None = None, system: str = "system") -> Rep:
    """`system` names the system prompt file (each system of kintsugi has its own, e.g. system_contact)."""
    from kintsugi.reasoning.base import RecordingReasoner

    inner = reasoner.inner if isinstance(reasoner, RecordingReasoner) else reasoner

    def answer(req: Req) -> Rep:
        if inner.name == "embedded":
            out = embedded(req)
            return check(out) if check else out
        if hasattr(inner, "ask"):
            return inner.ask(role, req, reply, check=check, system=system)
        raise ReasoningError(f"reasoner backend {inner.name!r} does not answer the {role!r} role; "
                             f"use embedded or openai")

    if isinstance(reasoner, RecordingReasoner):
        return reasoner.record(role, answer, request)
    return answer(request)
