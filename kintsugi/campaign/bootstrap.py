"""Make a task's registration happen in this process (main or worker).

Workers are spawned fresh, so they must import the same plugin modules as the
main process. Built-in tasks are loaded only when the task is not already
provided by a plugin: a third-party task then does not pay for (or break on)
importing every built-in task.
"""

from __future__ import annotations

import importlib
import os

from kintsugi.core.errors import KintsugiError

_loaded: set[tuple[str, ...]] = set()


def bootstrap(plugins: list[str] | tuple[str, ...], task: str) -> None:
    """Import plugin modules, then built-in tasks if `task` is still unknown; raise if it stays unknown."""
    # Workers render headless; EGL is the default GL for MuJoCo there unless the user chose another.
    os.environ.setdefault("MUJOCO_GL", "egl")
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS

    key = (task, *plugins)
    if key in _loaded and task in TASKS:
        return
    for module in plugins:
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - report any import failure with what to do
            raise KintsugiError(
                f"could not import plugin module {module!r} ({type(exc).__name__}: {exc}); "
                "check that it is installed or on PYTHONPATH"
            ) from exc
    builtin_error: Exception | None = None
    if task not in TASKS:
        try:
            load_builtins()
        except Exception as exc:  # noqa: BLE001 - only fatal if the task stays unknown
            builtin_error = exc
    if task not in TASKS:
        known = ", ".join(TASKS.names()) or "(none)"
        hint = f"; loading built-in tasks failed: {type(builtin_error).__name__}: {builtin_error}" if builtin_error else ""
        raise KintsugiError(
            f"unknown task {task!r}; known: {known}{hint}. "
            "If it is a third-party task, list its module under `plugins`."
        )
    _loaded.add(key)
