"""docs/add-a-task.md's contact example runs as written: its task registers, coral (the default and reference
method, no hand-written expert) runs it from its instruction, and its scorer judges the truth."""

from __future__ import annotations

import re
import sys
import types
from pathlib import Path

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import numpy as np
import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import TrialSpec
from kintsugi.core.registry import TASKS
from kintsugi.core.runner import run_trial

DOC = Path(__file__).resolve().parents[3] / "docs" / "add-a-task.md"


def _example() -> str:
    blocks = re.findall(r"```python contact-example\n(.*?)```", DOC.read_text(), flags=re.S)
    assert len(blocks) == 1, "the contact section has one example"
    return blocks[0]


@pytest.fixture(scope="module", autouse=True)
def example_task():
    """The example registered for this module's tests only (other tests list the registered tasks)."""
    load_builtins()
    module = types.ModuleType("add_a_contact_task_example")  # a real module, as a user's file would be
    sys.modules[module.__name__] = module
    exec(compile(_example(), str(DOC), "exec"), module.__dict__)
    yield
    TASKS._entries.pop("can-to-wall", None)
    sys.modules.pop(module.__name__, None)


def test_the_example_needs_no_expert_and_coral_runs_it_from_its_instruction() -> None:
    task = TASKS.get("can-to-wall").factory()
    assert task.reference_method == "coral" and task.default_method == "coral"
    record = run_trial(TrialSpec(task="can-to-wall", method=task.default_method, variant="default", condition="all",
                                 seed=1, overrides=dict(task.contract_overrides)))
    assert record.error is None, record.error
    assert record.physics_steps > 0 and {"can.diameter_m", "can.mass_kg", "wall.x_m"} <= set(record.params)
    assert task.config({"can.mass_kg": [0.8, 1.0]}).can.mass_kg == (0.8, 1.0)


def test_the_examples_scorer_judges_the_truth() -> None:
    task = TASKS.get("can-to-wall").factory()
    cfg = task.config({})
    world, scorer, setup = task.build(cfg, "none", 0)
    try:
        assert not scorer.finish(world)[0]  # where it starts: away from the wall
        a = world.layout.obj_qpos["can"]
        wall = setup.scene.fixtures["wall"]
        world.data.qpos[a] = wall.pos[0] - wall.half[0] - setup.scene.geometry["can"].parts[0].radius + 0.001
        world.step(200)
        ok, figures = scorer.finish(world)
        assert ok and figures.at_wall, figures
        world.data.qpos[a + 3:a + 7] = np.array([0.7071068, 0.7071068, 0.0, 0.0])  # knocked over against it
        world.step(200)
        assert not scorer.finish(world)[0]
    finally:
        world.close()
