"""One contract over every registered task and its default variants (dm_control suite_test style).

A new task passes this file or it is not done: it builds, a trial runs with no error, the
physics steps with no MuJoCo warning and no NaN, the same seed gives the same record, and
different seeds under condition "all" sample different hidden parameters. Broken inputs
(unknown method, variant, condition, override) become a recorded error, never an exception.
"""

from __future__ import annotations

import functools
import math
from typing import Any, Callable

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest

from kintsugi.core.plugins import load_builtins

from kintsugi.core.registry import TASKS
from kintsugi.core.record import TrialRecord, TrialSpec
from kintsugi.core.runner import run_trial

load_builtins()
BUILTIN = [e for e in TASKS if e.factory.__module__.startswith("kintsugi.")]
"""Tasks kintsugi ships (test plugins such as tests.fake_tasks may register extra ones)."""
CASES = [(e.name, v) for e in BUILTIN for v in e.factory().default_variants]


def _step_peg_world(variant: str, condition: str, seed: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Build the peg world directly and drive it through the taught skills (contacts included)."""
    from kintsugi.worlds.peg.conditions import sample_params
    from kintsugi.worlds.peg.config import PegTaskConfig
    from kintsugi.worlds.peg.goals import full_goals, load_goals
    from kintsugi.worlds.peg.skills import SEQUENCE, execute_skill
    from kintsugi.worlds.peg.world import HOME_POSE, PegWorld

    cfg = PegTaskConfig()
    world = PegWorld(cfg, sample_params(cfg, variant, condition, seed))
    goals = full_goals(load_goals(), HOME_POSE)
    for skill in SEQUENCE:
        execute_skill(world, skill, goals[skill])
    world.close()
    assert world.steps > 1000
    return world.model, world.data


def _step_tabletop_world(task: str, variant: str, condition: str, seed: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Build a tabletop task's world directly and run its scripted sequence (grasps included)."""
    from kintsugi.worlds.tabletop.task import run_script

    factory = TASKS.get(task).factory()
    world = run_script(factory, condition, seed, dict(getattr(factory, "contract_overrides", {})))
    world.close()
    assert world.steps > 1000
    return world.model, world.data


def _step_contact_world(task: str, variant: str, condition: str, seed: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Build a contact task's evaluation world and drive it with its reference method (MPPI, contacts)."""
    from kintsugi.worlds.contact.task import run_reference

    factory = TASKS.get(task).factory()
    world = run_reference(factory, condition, seed, overrides=dict(factory.contract_overrides))
    world.close()
    assert world.steps > 1000
    return world.model, world.data


WORLD_STEPPERS: dict[str, Callable[[str, str, int], tuple[mujoco.MjModel, mujoco.MjData]]] = {
    "peg-insertion": _step_peg_world,
} | {e.name: functools.partial(_step_tabletop_world, e.name) for e in BUILTIN if "tabletop" in e.tags
     } | {e.name: functools.partial(_step_contact_world, e.name) for e in BUILTIN if "contact" in e.tags}
"""How to build and step each task's world directly, to read MuJoCo's warning counters."""


def _spec(task: str, variant: str, seed: int = 0, condition: str = "all", **kw: Any) -> TrialSpec:
    factory = TASKS.get(task).factory()
    method = getattr(factory, "reference_method", "baseline")
    kw.setdefault("overrides", dict(getattr(factory, "contract_overrides", {})))  # a task's short contract budget
    return TrialSpec(task=task, method=method, variant=variant, condition=condition, seed=seed, **kw)


def _floats(value: Any) -> list[float]:
    if isinstance(value, float):
        return [value]
    if isinstance(value, dict):
        return [f for v in value.values() for f in _floats(v)]
    if isinstance(value, (list, tuple)):
        return [f for v in value for f in _floats(v)]
    return []


def _sampled(record: TrialRecord) -> dict[str, Any]:
    """The hidden parameters drawn for the trial (not outcomes such as the final tip depth)."""
    return {k: v for k, v in record.params.items() if not k.startswith("tip_")}


def test_every_builtin_task_is_covered() -> None:
    assert BUILTIN, "no task registered by kintsugi.worlds.load_builtins()"
    for entry in BUILTIN:
        task = entry.factory()
        assert task.default_variants, f"{entry.name} has no default variants"
        assert "all" in task.conditions and "none" in task.conditions
        assert entry.name in WORLD_STEPPERS, f"add a world stepper for task {entry.name!r} to this file"


@pytest.mark.parametrize(("task", "variant"), CASES)
def test_task_contract(task: str, variant: str) -> None:
    # Builds and runs a trial, with no error and no NaN anywhere in the record.
    first = run_trial(_spec(task, variant, seed=0))
    assert first.error is None, first.error
    assert first.physics_steps > 0 and first.sim_time > 0 and first.skills
    assert all(math.isfinite(f) for f in _floats(first.model_dump(mode="python"))), first
    # Same seed -> identical record apart from wall-clock timings.
    again = run_trial(_spec(task, variant, seed=0))
    assert again.without_timings() == first.without_timings()
    # Different seeds under "all" -> different hidden parameters (every randomized one moves).
    other = run_trial(_spec(task, variant, seed=1))
    assert other.error is None, other.error
    a, b = _sampled(first), _sampled(other)
    assert a.keys() == b.keys()
    differing = {k for k in a if a[k] != b[k]}
    assert differing, f"seeds 0 and 1 sampled the same parameters: {a}"
    # Stepping the world directly: no MuJoCo warning of any kind, finite state.
    model, data = WORLD_STEPPERS[task](variant, "all", 2)
    warnings = {mujoco.mjtWarning(i).name: data.warning[i].number
                for i in range(mujoco.mjtWarning.mjNWARNING) if data.warning[i].number}
    assert not warnings, warnings
    for name in ("qpos", "qvel", "qacc", "act", "sensordata"):
        assert np.all(np.isfinite(getattr(data, name))), name
    assert data.ncon >= 0 and data.time > 0


@pytest.mark.parametrize("task", [e.name for e in BUILTIN])
def test_condition_none_is_the_nominal_world(task: str) -> None:
    """Seeds differ only where the condition randomizes: under "none" the hidden truth is fixed."""
    a = run_trial(_spec(task, TASKS.get(task).factory().default_variants[0], seed=0, condition="none"))
    b = run_trial(_spec(task, TASKS.get(task).factory().default_variants[0], seed=7, condition="none"))
    assert a.error is None and b.error is None
    assert _sampled(a) == _sampled(b)


@pytest.mark.parametrize(("field", "value", "needles"), [
    ("method", "no-such-method", ["unknown method 'no-such-method'", "baseline"]),
    ("variant", "hexagon", ["unknown peg shape 'hexagon'", "round"]),
    ("variant", "polygon2", ["unknown peg shape 'polygon2'", "polygonN"]),
    ("condition", "storm", ["unknown condition 'storm'", "friction", "pose", "all"]),
    ("task", "no-such-task", ["unknown task 'no-such-task'", "peg-insertion"]),
])
def test_bad_names_become_a_recorded_error(field: str, value: str, needles: list[str]) -> None:
    fields = {"task": "peg-insertion", "method": "baseline", "variant": "round", "condition": "all", "seed": 0}
    fields[field] = value
    record = run_trial(TrialSpec(**fields))  # must not raise
    assert record.error, record
    for needle in needles:
        assert needle in record.error, record.error
    assert not record.success and not record.framework_success
    assert record.key == TrialSpec(**fields).key


def test_bad_override_becomes_a_recorded_error() -> None:
    record = run_trial(_spec("peg-insertion", "round", overrides={"hole.no_such_key": 1}))
    assert record.error and "ConfigError" in record.error and "hole.no_such_key" in record.error
    record = run_trial(_spec("peg-insertion", "round", overrides={"peg.clearance_mm": -1}))
    assert record.error and "peg.clearance_mm" in record.error
