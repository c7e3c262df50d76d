"""Make a task's registration happen in this process (main or worker).

Workers are spawned fresh, so they import the same plugin modules as the main process
(a campaign's `plugins`, `kintsugi bench --plugin`): the built-ins and installed entry points
first, then each plugin module (`kintsugi.core.plugins.load_plugins`), so a plugin task can
be run by a built-in method and a plugin method can run a built-in task.
"""

from __future__ import annotations

import os

from kintsugi.core.errors import KintsugiError

_loaded: set[tuple[str, ...]] = set()


def bootstrap(plugins: list[str] | tuple[str, ...], task: str) -> None:
    """Import the built-ins and plugin modules; raise a one-line error if `task` stays unknown."""
    # Workers render headless; EGL is the default GL for MuJoCo there unless the user chose another.
    os.environ.setdefault("MUJOCO_GL", "egl")
    from kintsugi.core.plugins import load_plugins
    from kintsugi.core.registry import TASKS

    key = (task, *plugins)
    if key in _loaded and task in TASKS:
        return
    load_plugins(plugins)
    if task not in TASKS:
        known = ", ".join(TASKS.names()) or "(none)"
        raise KintsugiError(
            f"unknown task {task!r}; known: {known}. "
            "If it is a third-party task, name its module with --plugin (a campaign's `plugins`)."
        )
    _loaded.add(key)
