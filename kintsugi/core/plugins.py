"""Where registry entries come from: the built-in modules, a user's `--plugin` modules, and the
`kintsugi.plugins` entry-point group of installed packages (Gymnasium's pattern).

Built-ins are named by string and imported on first need, so `core` never imports the layers
above it and `import kintsugi` stays light.
"""

from __future__ import annotations

import importlib
from importlib.metadata import entry_points

from kintsugi.core.errors import ConfigError

BUILTIN_MODULES = (
    "kintsugi.worlds.peg.task",
    "kintsugi.worlds.tabletop.tasks",
    "kintsugi.worlds.contact.tasks",
    "kintsugi.methods.builtin",
)
ENTRY_POINT_GROUP = "kintsugi.plugins"
_loaded: set[str] = set()


def load_builtins() -> None:
    """Import the built-in tasks and methods and every installed plugin (once per process)."""
    for module in BUILTIN_MODULES:
        _import(module)
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.value not in _loaded:
            try:
                ep.load()
            except Exception as exc:  # noqa: BLE001 - name the package whose plugin is broken
                raise ConfigError(f"plugin entry point {ep.name!r} ({ep.value}) failed to load: "
                                  f"{type(exc).__name__}: {exc}") from exc
            _loaded.add(ep.value)


def load_plugins(modules: list[str] | tuple[str, ...]) -> None:
    """Import a user's plugin modules (each registers its tasks, methods or backends)."""
    load_builtins()
    for module in modules:
        try:
            _import(module)
        except ModuleNotFoundError as exc:
            if exc.name and module.startswith(exc.name):
                raise ConfigError(f"plugin module {module!r} not found; it must be importable "
                                  "(on PYTHONPATH or installed)") from None
            raise


def _import(module: str) -> None:
    if module not in _loaded:
        importlib.import_module(module)
        _loaded.add(module)
