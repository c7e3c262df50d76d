"""A model backend is told everything the validators accept: every template function the composer's
template filler reads, every constraint kind the task-graph parser accepts, and every field of the composer's
request and reply are documented in the prompts (listed from the code, so a new one fails here until the
prompt names it)."""

from __future__ import annotations

import re
import typing

from kintsugi.methods.agentchord import templates
from kintsugi.methods.agentchord.types import ComposerReply, ComposerRequest
from kintsugi.reasoning.roles import read_prompt
from kintsugi.taskgraph import constraints

PACKAGE = "kintsugi.methods.agentchord"


def _prompt(name: str) -> str:
    return read_prompt(PACKAGE, f"prompts/{name}.md")


def template_functions() -> set[str]:
    names: set[str] = set()
    for pattern in (v.pattern for k, v in vars(templates).items() if isinstance(v, re.Pattern)):
        m = re.match(r"\^\\\$\(([a-z0-9|]+)\)", pattern)
        if m:
            names |= set(m.group(1).split("|"))
    return names


def constraint_kinds() -> set[str]:
    members = typing.get_args(typing.get_args(constraints.Constraint)[0])
    return {m.model_fields["kind"].default for m in members}


def test_the_validators_lists_are_read_from_the_code() -> None:
    assert {"x", "mirror", "thin", "dx", "turn", "rx"} <= template_functions()
    assert {"heading", "within", "upright", "in_region"} <= constraint_kinds()


def test_composer_prompt_documents_every_template_function() -> None:
    text = _prompt("composer")
    missing = sorted(f for f in template_functions() if f"${f}(" not in text)
    assert not missing, f"composer.md does not document the templates {missing}"


def test_system_prompt_documents_every_constraint_kind() -> None:
    text = _prompt("system_taskgraph")
    missing = sorted(k for k in constraint_kinds() if not re.search(rf"\b{k}\(", text))
    assert not missing, f"system_taskgraph.md does not document the constraint kinds {missing}"


def test_composer_prompt_names_every_request_and_reply_field() -> None:
    text = _prompt("composer")
    fields = (set(ComposerRequest.model_fields) | set(ComposerReply.model_fields)) - {"images_png"}
    missing = sorted(f for f in fields if f"`{f}`" not in text)
    assert not missing, f"composer.md does not name the fields {missing}"
