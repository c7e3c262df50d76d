"""Reasoning: the role protocol (`roles.ask`), the transcript, and the backends that answer.

Backends register in `REASONERS` (kept in `kintsugi.core.registry` beside the task and method
registries) a factory `factory(settings: ReasonerSettings, options) -> Reasoner` paired with their
own settings class (`Entry.config`), which validates `ReasonerSettings.options` (`--set
reasoner.options.<key>=value`, applied by `reasoner_settings`). The built-ins are `embedded` (each role's offline answer),
`scripted` (replies from a file, a record or a function) and `openai` (any OpenAI-compatible
endpoint; its SDK is imported only when that backend is built). Nothing here imports a method:
each method package registers the roles it asks.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any, Callable

from kintsugi.core.registry import NoSettings, REASONERS
from kintsugi.core.resolve import backend_options, reasoner_settings

if TYPE_CHECKING:
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.reasoning.base import Reasoner

ReasonerFactory = Callable[["ReasonerSettings", Any], "Reasoner"]
"""(the common settings, the backend's own validated options) -> a backend."""

_BUILTIN_BACKENDS = ("kintsugi.reasoning.builtin",)


def load_builtin_backends() -> None:
    """Import the built-in backend registrations (light: no SDK is imported until a backend is built)."""
    for module in _BUILTIN_BACKENDS:
        importlib.import_module(module)


def make_reasoner(settings: "ReasonerSettings") -> "Reasoner":
    """Build the backend named by `settings.backend` (unknown names list the known ones)."""
    load_builtin_backends()
    from kintsugi.reasoning.first_requests import wrap

    entry = REASONERS.get(settings.backend)
    return wrap(entry.factory(settings, backend_options(entry, settings.options)))


__all__ = ["REASONERS", "NoSettings", "ReasonerFactory", "backend_options", "load_builtin_backends",
           "make_reasoner", "reasoner_settings"]
