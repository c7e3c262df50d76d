"""kintsugi: resilient robot manipulation on real MuJoCo physics.

`kintsugi.run(task, ...)`, `kintsugi.bench(task, ...)` and `kintsugi.default_config(task)` are the Python
API (`kintsugi.api`); they load on first use, so `import kintsugi` stays light.
"""

import importlib
import os

# Headless offscreen rendering; must be set before mujoco is first imported.
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"

_API = frozenset({"run", "bench", "campaign", "default_config", "ConfigError", "KintsugiError"})


def __getattr__(name: str):  # noqa: ANN202 - PEP 562: the API's names, imported on first use
    if name in _API:
        return getattr(importlib.import_module("kintsugi.api"), name)
    raise AttributeError(f"module 'kintsugi' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])
