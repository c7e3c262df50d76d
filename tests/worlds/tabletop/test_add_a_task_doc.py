"""docs/add-a-task.md's example runs as written: its task registers, the scripted reference solves it, and
AgentChord's embedded composer plans it from its instruction alone."""

from __future__ import annotations

import re
from pathlib import Path

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import TrialSpec
from kintsugi.core.registry import TASKS
from kintsugi.core.runner import run_trial

DOC = Path(__file__).resolve().parents[3] / "docs" / "add-a-task.md"


def _example() -> str:
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
    assert len(blocks) == 1, "the guide has one example"
    return blocks[0]


@pytest.fixture(scope="module", autouse=True)
def example_task():
    """The example registered for this module's tests only (other tests list the registered tasks)."""
    load_builtins()
    exec(compile(_example(), str(DOC), "exec"), {"__name__": "add_a_task_example"})
    yield
    TASKS._entries.pop("green-left-of-purple", None)


def test_the_guides_example_task_runs() -> None:
    record = run_trial(TrialSpec(task="green-left-of-purple", method="scripted", variant="default", condition="pose",
                                 seed=1))
    assert record.error is None, record.error
    assert record.success, record.task_figures
    task = TASKS.get("green-left-of-purple").factory()
    assert task.config({"objects.green_block.mass_kg": 0.1}).objects.green_block.mass_kg == 0.1


def test_agentchord_plans_the_example_from_its_instruction() -> None:
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.methods.agentchord.compile import compile_graph
    from kintsugi.reasoning import make_reasoner

    task = TASKS.get("green-left-of-purple").factory()
    # At the middle of its range the green block already stands 20 cm left of the purple one and 7 cm behind it,
    # which the scorer's left_of (within 8 cm front to back) accepts: the goal would hold before anything moves.
    # Drawn 10 cm behind, it must be moved.
    cfg = task.config({"objects.green_block.x_m": (0.36, 0.36)})
    episode = task.episode(cfg, "default", "none", 0)
    try:
        compiled = compile_graph(make_reasoner(ReasonerSettings()), task.spec,
                                 episode.robot.observation(images=False), cfg=cfg)
    finally:
        episode.close()
    assert "left_of(green_block, purple_block)" in compiled.composer.goal
    ops = list(compiled.composer.edge_operators.values())
    assert ops[0] == "grasp(left, green_block)" and "put_left_of(left, green_block, purple_block)" in ops
