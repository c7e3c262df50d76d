"""The role registry and `ask`: every reasoning call of every system, on any backend, in one transcript.

A `Role` is what a method asks a reasoner: a name, its request and reply types, its prompt files
(package data beside the method that owns the role: `<package>/prompts/<name>.md` and the
system prompt `<package>/prompts/<system>.md`), an optional `check(reply, request)` and the
embedded answer (a plain function request -> reply). The method package that asks a role
registers it (`ROLES.register(Role(...))`, e.g. `kintsugi.methods.recovery.roles`).

`ask(reasoner, role_name, request)` hands the request to the backend, which decides how to
answer: the embedded backend calls the role's embedded function, a model endpoint gets the
prompts and the request, the scripted backend replays replies. The role's check (and a per-call
`check` with context the request does not carry) runs on every reply, whichever backend gave
it: it may raise BadReply (an endpoint is then asked once to repair) or return a corrected
reply. When the reasoner records (RecordingReasoner), the call lands in the transcript under
the role's name, failed calls included.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any, Callable, Iterator

from pydantic import BaseModel, ValidationError

from kintsugi.core.errors import ConfigError, ReasoningError, UnknownNameError
from kintsugi.reasoning.base import Check
from kintsugi.reasoning.jsontext import BadReply, describe_validation_error


@dataclass(frozen=True)
class ToolRoute:
    """How a reply arrives as function calls from a model endpoint in strict mode (e.g. a plan, one tool
    per skill).

    `to_data` turns the ordered calls `[(name, arguments)]` into data for the reply model; in text
    mode the model writes that data as JSON itself, following `text_hint` and the tools' descriptions.
    """

    tools: list[dict[str, Any]]
    to_data: Callable[[list[tuple[str, dict[str, Any]]]], Any]
    text_hint: str = ""

    @property
    def names(self) -> list[str]:
        return [t["function"]["name"] for t in self.tools]


@dataclass(frozen=True)
class Role:
    """One question a method asks a reasoner, and everything a backend needs to answer it."""

    name: str
    request: type[BaseModel]
    reply: type[BaseModel]
    package: str
    """The method package that owns the role; its prompts are package data under `<package>/prompts/`."""
    embedded: Callable[[Any], BaseModel] | None = None
    """The offline answer: request -> reply (the embedded backend calls it)."""
    check: Callable[[Any, Any], Any] | None = None
    """`check(reply, request)` -> the reply to use; raises ReasoningError (BadReply) to reject it."""
    system: str = "system"
    """The system prompt's name: `<package>/prompts/<system>.md`."""
    prompt: str | None = None
    """The role prompt's name when it is not the role's own: `<package>/prompts/<prompt>.md`."""
    sections: Callable[[Any], str] | None = None
    """Extra markdown for the user message, written from the request (e.g. the peg robot's description)."""
    tools: Callable[[Any], ToolRoute] | None = None
    """For replies a model endpoint should give as function calls: the tools for this request."""
    image_labels: dict[str, str] = field(default_factory=dict)
    """What each image of the request shows, by its dotted path (`outcome.image_png`), told to a model."""
    image_max_px: int = 512
    """The longest side an image needs for this role; larger camera images are scaled down before sending."""
    sends_images: bool | None = None
    """Whether the role's requests carry camera images; None: they may whenever the request type has image
    (bytes) fields. A role whose method never fills them says False, so a text-only endpoint can serve it."""

    @property
    def prompt_file(self) -> str:
        return f"prompts/{self.prompt or self.name}.md"

    @property
    def prompt_path(self) -> str:
        """Where the role's prompt lives in the source tree, for messages that send the user to it."""
        return f"{self.package.replace('.', '/')}/{self.prompt_file}"

    def prompt_text(self) -> str:
        return read_prompt(self.package, self.prompt_file)

    def system_text(self) -> str:
        return read_prompt(self.package, f"prompts/{self.system}.md")

    def checker(self, request: BaseModel, extra: Check | None = None) -> Check | None:
        """The role's check bound to `request`, followed by the caller's `extra` one; None when neither."""
        own = self.check
        if own is None:
            return extra
        if extra is None:
            return lambda reply: own(reply, request)
        return lambda reply: extra(own(reply, request))


@lru_cache(maxsize=None)
def read_prompt(package: str, path: str) -> str:
    """Text of a prompt shipped as package data, so users can read and edit it."""
    try:
        return resources.files(package).joinpath(path).read_text(encoding="utf-8")
    except (FileNotFoundError, ModuleNotFoundError):
        raise ConfigError(f"prompt file {package.replace('.', '/')}/{path} is missing; the role's method "
                          f"package must ship it (pyproject [tool.setuptools.package-data])") from None


class RoleRegistry:
    """Role name -> Role; an unknown name raises with the registered ones listed."""

    def __init__(self) -> None:
        self._roles: dict[str, Role] = {}

    def register(self, role: Role) -> Role:
        if role.name in self._roles:
            raise ValueError(f"role {role.name!r} registered twice")
        self._roles[role.name] = role
        return role

    def get(self, name: str) -> Role:
        try:
            return self._roles[name]
        except KeyError:
            known = ", ".join(sorted(self._roles)) or "(none)"
            raise UnknownNameError(f"unknown role {name!r}; known: {known} (a role registers when the method "
                                   f"module that asks it is imported)") from None

    def __contains__(self, name: str) -> bool:
        return name in self._roles

    def __iter__(self) -> Iterator[Role]:
        return iter(sorted(self._roles.values(), key=lambda r: r.name))

    def names(self) -> list[str]:
        return sorted(self._roles)


ROLES = RoleRegistry()


def ask(reasoner: Any, role_name: str, request: BaseModel, check: Check | None = None) -> Any:
    """Ask `reasoner` the registered role `role_name`; the reply is of the role's reply type and has passed
    the role's check and `check` (a per-call one, for context the request does not carry)."""
    role = ROLES.get(role_name)
    if not isinstance(request, role.request):
        raise TypeError(f"role {role.name!r} takes a {role.request.__name__}, not a {type(request).__name__}")
    reply = reasoner.answer(role, request, role.checker(request, check))
    if not isinstance(reply, role.reply):
        raise ReasoningError(f"backend {reasoner.name!r} answered role {role.name!r} with a "
                             f"{type(reply).__name__}, not a {role.reply.__name__}")
    return reply


def parse_reply(role: Role, data: Any, check: Check | None = None) -> BaseModel:
    """Untrusted reply data (e.g. a decoded JSON object) -> the role's reply, validated and checked as a
    model's would be; BadReply says what is wrong."""
    if isinstance(data, role.reply):
        reply = data
    else:
        try:
            reply = role.reply.model_validate(data)
        except ValidationError as exc:
            raise BadReply(f"the {role.name} reply does not match the schema: {describe_validation_error(exc)}") from None
    return check(reply) if check is not None else reply


__all__ = ["ROLES", "Role", "RoleRegistry", "ToolRoute", "ask", "parse_reply", "read_prompt"]
