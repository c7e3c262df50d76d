"""A coral trial's first moment on a contact task: its context, config, first observation and formulation
request (what the formulation role is asked), for tests of the cost-code variables and stage seeds."""

from __future__ import annotations

from typing import Any


def coral_scene(task_name: str, seed: int) -> tuple[Any, Any, Any, Any, Any]:
    """(ctx, cfg, first observation, formulation request, evaluation world); the caller closes the world."""
    import kintsugi.worlds.contact.tasks  # noqa: F401
    from kintsugi.methods.coral.method import VARIANTS, Coral
    from kintsugi.core.registry import TASKS
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.worlds.contact.robot import ContactRobot

    task = TASKS.get(task_name).factory()
    cfg = task.config({})
    world, _, setup = task.build(cfg, "all", seed)
    ctx = task.context(cfg, setup, False, ReasonerSettings(), seed)
    obs = ContactRobot(world).observe()
    return ctx, cfg, obs, Coral(ctx, VARIANTS["coral"]).scene_request(obs, {}), world
