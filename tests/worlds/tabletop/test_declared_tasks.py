"""Tasks declared in one file (stack-blocks, flank-box, block-in-bin): their objects and regions are the
task's own config, an undeclared or shapeless object is a clear error, the scripted sequence solves each
and the ground-truth goal scorer refuses a run that skips the relation the task is about."""

from __future__ import annotations

from typing import Any, Callable

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import pytest

from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import TrialSpec
from kintsugi.core.registry import TASKS
from kintsugi.core.runner import run_trial
from kintsugi.worlds.tabletop.judge import goal_scorer
from kintsugi.worlds.tabletop.config import ObjectSection, ObjectsSection, TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.spec import TaskSpec
from kintsugi.worlds.tabletop.task import TabletopTask

load_builtins()
DECLARED = ("stack-blocks", "flank-box", "block-in-bin")


def _spec(**kw: Any) -> TaskSpec:
    base = dict(name="t", description="t", objects=("cube",), instruction="x", goal=("released(cube)",),
                script=lambda obs: [], scorer=goal_scorer(("released", "cube")),
                declared={"cube": ObjectSection(shape="box", size_m=(0.02, 0.02, 0.02), mass_kg=0.1,
                                                x_m=(0.4, 0.4), y_m=(0.0, 0.0))})
    return TaskSpec(**{**base, **kw})


def test_declared_objects_are_the_tasks_own_config() -> None:
    task = TASKS.get("stack-blocks").factory()
    cfg = task.config({"objects.red_block.mass_kg": 0.3})
    assert cfg.objects.red_block.mass_kg == 0.3 and cfg.objects.red_block.shape == "box"
    assert cfg.objects.red_block.rgba[0] > 0.8  # colour "red" sets the rgba
    assert cfg.objects.bottle.mass_kg == TabletopConfig().objects.bottle.mass_kg  # the shared ones stay
    with pytest.raises(ConfigError):
        task.config({"objects.red_block.massive": 1})
    assert "red_block" not in ObjectsSection.model_fields  # no shared config changed
    assert type(task.config({})) is type(TASKS.get("stack-blocks").factory().config({}))  # one class per task


def test_an_undeclared_or_clashing_object_is_a_clear_error() -> None:
    with pytest.raises(ConfigError, match="neither built in .* nor declared"):
        TabletopTask(_spec(objects=("cube", "ghost")))
    with pytest.raises(ConfigError, match="built-in object's name"):
        TabletopTask(_spec(objects=("cup",), declared={"cup": _spec().declared["cube"]}))
    with pytest.raises(ConfigError, match="not in TaskSpec.objects"):
        TabletopTask(_spec(objects=()))


def test_an_object_without_a_shape_is_an_error_not_a_box() -> None:
    objects = ObjectsSection()
    with pytest.raises(ConfigError, match="no object 'ghost'"):
        shape_of("ghost", objects)
    with pytest.raises(ValueError, match="colour"):
        ObjectSection(shape="box", size_m=(0.02, 0.02, 0.02), mass_kg=0.1, x_m=(0.4, 0.4), y_m=(0, 0), colour="teal")
    with pytest.raises(ValueError, match="wall_m"):
        ObjectSection(shape="sphere", size_m=(0.02, 0, 0), mass_kg=0.1, x_m=(0.4, 0.4), y_m=(0, 0), wall_m=0.005)


@pytest.mark.parametrize("shape,size", [("box", (0.02, 0.03, 0.01)), ("cylinder", (0.03, 0.05, 0.0)),
                                        ("sphere", (0.025, 0.0, 0.0)), ("capsule", (0.02, 0.03, 0.0))])
def test_each_primitive_builds_and_rests_on_the_table(shape: str, size: tuple) -> None:
    task = TabletopTask(_spec(declared={"cube": ObjectSection(shape=shape, size_m=size, mass_kg=0.1,
                                                              x_m=(0.4, 0.4), y_m=(0.0, 0.0))}))
    world, _, _, _ = task.build(task.config({}), "none", 0)
    z0 = world.ground_truth().objects["cube"].pos[2]
    for _ in range(50):
        world.tick()
    truth = world.ground_truth().objects["cube"]
    assert abs(truth.pos[2] - z0) < 0.003 and truth.speed_m_s < 0.02
    assert abs(z0 - shape_of("cube", world.cfg.objects).rest_height) < 1e-3
    world.close()


@pytest.mark.parametrize("task", DECLARED)
def test_scripted_method_solves_the_declared_task(task: str) -> None:
    record = run_trial(TrialSpec(task=task, method="scripted", variant="default", condition="pose", seed=3))
    assert record.error is None, record.error
    assert record.success and record.framework_success, record.task_figures


def _play(task: str, edit: Callable[[list[dict[str, Any]]], list[dict[str, Any]]], seed: int = 5) -> dict:
    t = TASKS.get(task).factory()
    world, scorer, hook, _ = t.build(t.config({}), "pose", seed)
    robot = TabletopRobot(world, hook=hook)
    for action in edit(t.spec.script(robot.observation(images=False))):
        robot.execute(action)
    ok, details = scorer.finish(world)
    world.close()
    return {"ok": ok, **details.checks}


def _place_beside(script: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = [dict(a) for a in script]
    for a in out:
        if a["action"] == "place":
            a["y"] += 0.12
            a.pop("z_offset", None)
    return out


def test_the_scorer_refuses_a_block_set_beside_instead_of_on() -> None:
    d = _play("stack-blocks", _place_beside)
    assert not d["ok"] and not d["on(red_block, blue_block)"] and d["released(red_block)"]


def test_the_scorer_refuses_a_block_set_beside_the_bin() -> None:
    d = _play("block-in-bin", _place_beside)
    assert not d["ok"] and not d["inside(orange_block, bin)"]


def test_the_scorer_refuses_cans_on_the_wrong_sides() -> None:
    def swap(script: list[dict[str, Any]]) -> list[dict[str, Any]]:
        out = []
        for a in script:
            a = {**a, "left": dict(a["left"]), "right": dict(a["right"])}
            if a["left"]["action"] == "place":
                a["left"]["x"] -= 0.15
                a["right"]["x"] -= 0.15
            out.append(a)
        return out

    d = _play("flank-box", swap)
    assert not d["ok"] and not d["left_of(green_can, box)"] and d["upright(green_can)"]
