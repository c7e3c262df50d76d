"""Reasoner backends behind one typed protocol (judge, analyze, plan).

Backends register a factory `factory(settings: ReasonerSettings) -> Reasoner`
in `REASONERS`; `make_reasoner` imports the built-in backend modules lazily so
their registration runs without making `import kintsugi` pull in the SDKs.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Callable

from kintsugi.core.registry import Registry

if TYPE_CHECKING:
    from kintsugi.reasoning.base import Reasoner
    from kintsugi.core.record import ReasonerSettings

ReasonerFactory = Callable[["ReasonerSettings"], "Reasoner"]

REASONERS: Registry[ReasonerFactory] = Registry("reasoner")

_BUILTIN_BACKENDS = ("kintsugi.methods.recovery.embedded", "kintsugi.reasoning.openai_backend")


def load_builtin_backends() -> None:
    """Import the built-in backend modules so they register; a backend module that
    does not exist yet is skipped, but an import error *inside* one is raised."""
    for module in _BUILTIN_BACKENDS:
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name != module:
                raise


def make_reasoner(settings: "ReasonerSettings") -> "Reasoner":
    """Build the backend named by `settings.backend` (unknown names list the known ones)."""
    load_builtin_backends()
    return REASONERS.get(settings.backend).factory(settings)


__all__ = ["REASONERS", "ReasonerFactory", "load_builtin_backends", "make_reasoner"]
