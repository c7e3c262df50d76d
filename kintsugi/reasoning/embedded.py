"""The embedded backend: every role answered by its own offline function, no model and no network.

Each role brings its embedded answer (`Role.embedded`, registered beside the method that asks
it); this backend only calls it and runs the role's check on the result, as it would on a model's
reply. A role without one is a clear ReasoningError naming the backends that can answer it.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel

from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning.base import CallStats, Check
from kintsugi.reasoning.roles import Role


class EmbeddedReasoner:
    """Answers with `role.embedded(request)`; deterministic, offline."""

    name = "embedded"
    sees_images = False
    """Optional camera images (a tabletop observation's) are left out of requests: the embedded answers read
    the perceived features. Images a request type always carries (the peg's PNGs) are still sent."""

    def __init__(self) -> None:
        self.last_stats: CallStats | None = None

    def answer(self, role: Role, request: BaseModel, check: Check | None = None) -> BaseModel:
        if role.embedded is None:
            raise ReasoningError(f"role {role.name!r} has no embedded answer; use a model backend (openai) or "
                                 f"replay replies with the scripted backend")
        reply = role.embedded(request)
        return check(reply) if check is not None else reply


def make_embedded(settings: Any, options: Any) -> EmbeddedReasoner:
    """Registry factory (the backend has no options)."""
    return EmbeddedReasoner()
