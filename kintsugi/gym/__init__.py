"""Gymnasium environments for every registered task: `kintsugi/<TaskName>-v0` (e.g. `kintsugi/PourSingle-v0`).

    import gymnasium as gym
    import kintsugi.gym  # registers the environments (or gym.make("kintsugi.gym:kintsugi/PourSingle-v0"))
    env = gym.make("kintsugi/PourSingle-v0", condition="drop", images=False)

Each id's kwargs name its task; any `KintsugiEnv` option may be passed to `gymnasium.make`.
"""

from __future__ import annotations

import gymnasium as gym

from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS

NAMESPACE = "kintsugi"


def env_id(task: str) -> str:
    return f"{NAMESPACE}/{''.join(p.capitalize() for p in task.replace('_', '-').split('-'))}-v0"


def register_envs() -> list[str]:
    """Register one environment per task in the task registry (built-ins and loaded plugins); their ids."""
    load_builtins()
    ids = []
    for entry in TASKS:
        eid = env_id(entry.name)
        if eid not in gym.registry:
            gym.register(id=eid, entry_point="kintsugi.gym.env:KintsugiEnv", kwargs={"task": entry.name},
                         disable_env_checker=True)
        ids.append(eid)
    return ids


ENV_IDS = register_envs()

__all__ = ["ENV_IDS", "env_id", "register_envs"]
