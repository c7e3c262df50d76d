"""Reasoning: the role protocol (`roles.ask`), the transcript, and the backends that answer.

Backends register in `REASONERS` a factory `factory(settings: ReasonerSettings, options) -> Reasoner`
paired with their own settings class (`Entry.config`), which validates `ReasonerSettings.options`
(`--set reasoner.options.<key>=value`). The built-ins are `embedded` (each role's offline answer),
`scripted` (replies from a file, a record or a function) and `openai` (any OpenAI-compatible
endpoint; its SDK is imported only when that backend is built). Nothing here imports a method:
each method package registers the roles it asks.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any, Callable

from pydantic import ValidationError

from kintsugi.core.config import StrictModel, apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.core.registry import Entry, NoSettings, Registry

if TYPE_CHECKING:
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.reasoning.base import Reasoner

ReasonerFactory = Callable[["ReasonerSettings", Any], "Reasoner"]
"""(the common settings, the backend's own validated options) -> a backend."""

REASONERS: Registry[ReasonerFactory] = Registry("reasoner")

_BUILTIN_BACKENDS = ("kintsugi.reasoning.builtin",)


def load_builtin_backends() -> None:
    """Import the built-in backend registrations (light: no SDK is imported until a backend is built)."""
    for module in _BUILTIN_BACKENDS:
        importlib.import_module(module)


def backend_options(entry: Entry, options: dict[str, Any]) -> StrictModel:
    """`options` validated by the backend's settings class; ConfigError names `reasoner.options.<key>`."""
    try:
        return entry.config.model_validate(dict(options))
    except ValidationError as exc:
        known = ", ".join(entry.config.model_fields) or "none"
        problems = []
        for err in exc.errors(include_url=False, include_input=False):
            key = ".".join(["reasoner.options", *(str(p) for p in err["loc"])])
            if err["type"] == "extra_forbidden":
                problems.append(f"unknown key {key!r} (the {entry.name} backend's options: {known})")
            else:
                problems.append(f"{key}: {err['msg']}")
        raise ConfigError(f"bad reasoner option: {'; '.join(problems)}") from None


def make_reasoner(settings: "ReasonerSettings") -> "Reasoner":
    """Build the backend named by `settings.backend` (unknown names list the known ones)."""
    load_builtin_backends()
    entry = REASONERS.get(settings.backend)
    return entry.factory(settings, backend_options(entry, settings.options))


def reasoner_settings(settings: "ReasonerSettings", overrides: dict[str, Any]) -> "ReasonerSettings":
    """`settings` with `reasoner.*` overrides applied (keys without the prefix: `model`, `options.replies`),
    checked: the backend must exist and its options pass its settings class. Errors are one line naming
    the key."""
    options = dict(settings.options)
    common: dict[str, Any] = {}
    for key, value in overrides.items():
        if key == "options":
            if not isinstance(value, dict):
                raise ConfigError(f"reasoner.options must be a JSON object of the backend's options, not {value!r}")
            options |= value
        elif key.startswith("options."):
            options[key.removeprefix("options.")] = value
        else:
            common[key] = value
    out = apply_overrides(settings, common, prefix="reasoner") if common else settings
    out = out.model_copy(update={"options": options})
    load_builtin_backends()
    backend_options(REASONERS.get(out.backend), options)
    return out


__all__ = ["REASONERS", "NoSettings", "ReasonerFactory", "backend_options", "load_builtin_backends",
           "make_reasoner", "reasoner_settings"]
