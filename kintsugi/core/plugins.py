"""Where registry entries come from: the built-in modules, a user's `--plugin` modules, and the
`kintsugi.plugins` entry-point group of installed packages (Gymnasium's pattern).

Built-ins are named by string and imported on first need, so `core` never imports the layers
above it and `import kintsugi` stays light. A plugin is any importable module whose import
registers entries (`TASKS`, `METHODS`, `REASONERS`); an installed package names such modules
under the entry-point group so that they load without `--plugin`:

    [project.entry-points."kintsugi.plugins"]
    my_tasks = "my_package.kintsugi_tasks"
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
    "kintsugi.reasoning.builtin",
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
                dist = getattr(getattr(ep, "dist", None), "name", None)
                where = f" of package {dist!r}" if dist else ""
                raise ConfigError(f"plugin entry point {ep.name!r}{where} ({ep.value}) failed to load: "
                                  f"{type(exc).__name__}: {_first_line(exc)}") from exc
            _loaded.add(ep.value)


def load_plugins(modules: list[str] | tuple[str, ...]) -> None:
    """Import the built-ins, then a user's plugin modules (each registers its tasks, methods or backends).

    A module that cannot be imported is a one-line ConfigError naming it: not found, or what its
    import raised (a missing dependency, a name registered twice, ...).
    """
    load_builtins()
    for module in modules:
        try:
            _import(module)
        except ModuleNotFoundError as exc:
            if exc.name and (module == exc.name or module.startswith(exc.name + ".")):
                raise ConfigError(f"plugin module {module!r} not found; it must be importable "
                                  "(on PYTHONPATH or installed)") from None
            raise ConfigError(f"plugin module {module!r} failed to import: {type(exc).__name__}: "
                              f"{_first_line(exc)}") from exc
        except Exception as exc:  # noqa: BLE001 - any failure of a user's module is named, not a traceback
            raise ConfigError(f"plugin module {module!r} failed to import: {type(exc).__name__}: "
                              f"{_first_line(exc)}") from exc


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [""])[0]


def _import(module: str) -> None:
    if module not in _loaded:
        importlib.import_module(module)
        _loaded.add(module)
