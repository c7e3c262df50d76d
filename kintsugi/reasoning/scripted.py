"""The scripted backend: replies from a file or a function, checked like a model's.

Replies come from

- a JSONL file, one reply per line: a bare reply object (for any role), or
  `{"role": "composer", "reply": {...}}` (only for that role), or `{"role": ..., "error": "..."}` (that
  call fails with the message); each call takes the first unused line that fits its role;
- a trial record `.json` (`TrialRecord`): its transcript's replies in order, each keyed by its role,
  a failed call replayed as the same failure; so a model's answers from one trial can be replayed
  offline (`--reasoner scripted --set reasoner.options.replies=runs/<record>.json`);
- a Python callable `(role_name, request) -> reply dict` (`reasoner.options.function=module:callable`,
  or `ScriptedReasoner(fn)` in tests).

Every reply is validated against the role's reply type and run through the role's checks, as a
model's reply is (there is no repair round: a rejected reply is a failed call). Running out of
replies is a ReasoningError, recorded in the transcript like any failed call.
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path
from typing import Any, Callable, Iterable

from pydantic import BaseModel, model_validator

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError, ReasoningError
from kintsugi.reasoning.base import CallStats, Check
from kintsugi.reasoning.roles import Role, parse_reply

ReplyFunction = Callable[[str, BaseModel], Any]
"""(role name, request) -> the reply (a dict, or the reply model itself); may raise ReasoningError."""


class ScriptedOptions(StrictModel):
    """`reasoner.options` of the scripted backend: exactly one source of replies."""

    replies: str | None = None
    """A JSONL file of replies, or a trial record .json whose transcript is replayed."""
    function: str | None = None
    """`module:callable` answering (role name, request) -> reply dict."""

    @model_validator(mode="after")
    def _one_source(self) -> "ScriptedOptions":
        if (self.replies is None) == (self.function is None):
            raise ValueError("set exactly one of replies (a JSONL file or a trial record .json) and function "
                             "(module:callable)")
        return self


class Scripted(StrictModel):
    """One scripted answer: a reply, or a failure; `role` None = for whichever role asks."""

    role: str | None = None
    reply: Any = None
    error: str | None = None


def load_replies(path: str | Path) -> list[Scripted]:
    """The answers in a JSONL file or a trial record .json; ConfigError names the file and line."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"scripted replies {path}: cannot read ({exc.strerror or exc})") from None
    if path.suffix == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"scripted replies {path}: not valid JSON ({exc})") from None
        if isinstance(data, dict) and isinstance(data.get("transcript"), list):
            return [Scripted(role=c.get("role"), reply=c.get("reply"),
                             error=c.get("error") if c.get("reply") is None else None)
                    for c in data["transcript"]]
        if isinstance(data, list):
            return [_entry(item, path, i + 1) for i, item in enumerate(data)]
        raise ConfigError(f"scripted replies {path}: a .json file must be a trial record (with a transcript) "
                          f"or a list of replies")
    out = []
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            item = json.loads(line)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"scripted replies {path}:{number}: not valid JSON ({exc.msg})") from None
        out.append(_entry(item, path, number))
    return out


def _entry(item: Any, path: Path, number: int) -> Scripted:
    if not isinstance(item, dict):
        raise ConfigError(f"scripted replies {path}:{number}: each reply must be a JSON object")
    if "role" in item and set(item) <= {"role", "reply", "error"} and ("reply" in item or "error" in item):
        return Scripted.model_validate(item)
    return Scripted(reply=item)


def import_function(spec: str) -> ReplyFunction:
    """`module:callable` -> the callable; ConfigError when it cannot be found."""
    module, _, attr = spec.partition(":")
    if not module or not attr:
        raise ConfigError(f"reasoner.options.function={spec!r} must look like module:callable")
    try:
        fn = getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise ConfigError(f"reasoner.options.function={spec!r}: {exc}") from None
    if not callable(fn):
        raise ConfigError(f"reasoner.options.function={spec!r} is not callable")
    return fn


class ScriptedReasoner:
    """Answers from a list of replies (a file's, a record's) or a function; see the module docstring."""

    name = "scripted"
    sees_images = False
    """Replayed replies were written already: requests need not carry rendered camera images."""

    def __init__(self, replies: ReplyFunction | Iterable[Scripted | dict] | str | Path, where: str = "") -> None:
        self.last_stats: CallStats | None = None
        self.function: ReplyFunction | None = None
        self.where = where
        self.calls = 0
        self._entries: list[Scripted] = []
        if callable(replies):
            self.function = replies
            self.where = where or getattr(replies, "__name__", "a function")
            return
        if isinstance(replies, (str, Path)):
            self.where = where or str(replies)
            replies = load_replies(replies)
        self._entries = [item if isinstance(item, Scripted) else _entry(item, Path(self.where or "replies"), 0)
                         for item in replies]
        self.where = self.where or "a list of replies"

    @property
    def remaining(self) -> int:
        return len(self._entries)

    def answer(self, role: Role, request: BaseModel, check: Check | None = None) -> BaseModel:
        self.calls += 1
        if self.function is not None:
            data = self.function(role.name, request)
            if data is None:
                raise ReasoningError(f"scripted {self.where} gave no reply for role {role.name!r}")
            return parse_reply(role, data, check)
        fits = next((i for i, e in enumerate(self._entries) if e.role in (None, role.name)), None)
        if fits is None:
            raise ReasoningError(f"scripted replies ran out: no reply left for role {role.name!r} (call "
                                 f"{self.calls}) in {self.where}")
        entry = self._entries.pop(fits)
        if entry.error is not None:
            raise ReasoningError(f"scripted failure for {role.name}: {entry.error}")
        return parse_reply(role, entry.reply, check)


def make_scripted(settings: Any, options: ScriptedOptions) -> ScriptedReasoner:
    """Registry factory: reasoner.options.replies (a file) or reasoner.options.function (module:callable)."""
    if options.function is not None:
        return ScriptedReasoner(import_function(options.function), where=options.function)
    return ScriptedReasoner(options.replies)


__all__ = ["ReplyFunction", "Scripted", "ScriptedOptions", "ScriptedReasoner", "load_replies", "make_scripted"]
