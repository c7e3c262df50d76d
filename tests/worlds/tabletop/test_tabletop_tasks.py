"""The tabletop tasks beyond pour-single: the scripted sequence solves each one, and each judge
refuses a run that skips what the task is about (the pour, the turn, the handover, the capsule)."""

from __future__ import annotations

from typing import Any, Callable

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import pytest

from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

load_builtins()
NEW = ("pour-dual", "rearrange-table", "handover-block", "coffee-tray")


def _play(task: str, edit: Callable[[list[dict[str, Any]]], list[dict[str, Any]]], seed: int = 5
          ) -> tuple[bool, dict[str, Any]]:
    """Run the task's script, edited, under `pose`; return the judge's verdict and details."""
    t = TASKS.get(task).factory()
    world, scorer, hook, _ = t.build(t.config({}), "pose", seed)
    robot = TabletopRobot(world, hook=hook)
    for action in edit(t.spec.script(robot.observation(images=False))):
        robot.execute(action)
    ok, details = scorer.finish(world)
    world.close()
    return ok, details.model_dump()


@pytest.mark.parametrize("task", NEW)
def test_scripted_method_solves_the_task(task: str) -> None:
    record = run_trial(TrialSpec(task=task, method="scripted", variant="default", condition="pose", seed=3))
    assert record.error is None, record.error
    assert record.success and record.framework_success, record.task_figures
    assert all(s.reached for s in record.skills)


def test_pour_dual_without_the_pour_fails() -> None:
    ok, d = _play("pour-dual", lambda s: [a for a in s if a["action"] != "rotate_eef"])
    assert not ok and not d["poured"]
    assert d["cup_placed"] and d["bottle_on_table"]  # everything else was done


def test_rearrange_without_the_turn_fails() -> None:
    # Placed across the plate's side (one end on the plate): in the region, released, but wrongly turned.
    ok, d = _play("rearrange-table", lambda s: [a for a in s if a["left"]["action"] != "rotate_eef"])
    assert not ok
    for utensil in ("fork", "spoon"):
        assert d[utensil]["in_region"] and d[utensil]["released"]
        assert d[utensil]["heading_err_deg"] > 60.0


def test_handover_block_placed_by_the_left_arm_alone_fails() -> None:
    def left_alone(script: list[dict[str, Any]]) -> list[dict[str, Any]]:
        return script[:2] + [{"action": "place", "arm": "left", "x": 0.40, "y": -0.25}, script[-1]]

    ok, d = _play("handover-block", left_alone)
    assert not ok
    assert d["picked"] and not d["handed_over"] and d["flat"] and d["released"]


def _let_go_over_the_region(script: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The scripted handover, then the right hand opens 8 cm above the target region instead of placing."""
    return script[:8] + [{"action": "move_to_target", "arm": "right", "xyz": (0.40, -0.25, 0.12),
                          "rpy_deg": (-90.0, 90.0, 0.0)},
                         {"action": "open_gripper", "arm": "right"}]


def test_handover_block_dropped_into_the_region_fails() -> None:
    ok, d = _play("handover-block", _let_go_over_the_region)
    assert not ok
    assert d["handed_over"] and d["drops"] == 1 and not d["placed"] and d["release_height_m"] > 0.03


def test_handover_block_picked_up_after_a_drop_and_placed_succeeds() -> None:
    """Appendix B judges at the end of execution: a drop the robot recovers from is not a failure."""
    ok, d = _play("handover-block", lambda s: _let_go_over_the_region(s) + [
        {"action": "back", "arm": "right"},
        {"action": "grasp", "arm": "right", "obj": "block", "pre_grasp_offset": 0.06},
        {"action": "place", "arm": "right", "x": 0.40, "y": -0.25},
        {"action": "back", "arm": "right"}])
    assert d["drops"] == 1 and d["placed"] and abs(d["release_height_m"]) <= 0.01, d
    assert ok, d


def test_coffee_tray_moved_without_the_capsule_fails() -> None:
    ok, d = _play("coffee-tray", lambda s: s[3:])
    assert not ok
    assert d["tray_in_region"] and d["tray_flat"] and not d["capsule_in_tray"]


def test_tasks_offer_only_the_disturbances_they_have() -> None:
    assert set(TASKS.get("pour-single").factory().conditions) >= {"none", "pose", "drop", "shift", "knock", "all"}
    rearrange = TASKS.get("rearrange-table").factory()
    assert "knock" not in rearrange.conditions and "shift" in rearrange.conditions
    with pytest.raises(ConfigError, match="unknown condition 'knock'.*shift"):
        rearrange.build(rearrange.config({}), "knock", 0)


@pytest.mark.parametrize(("overrides", "key"), [
    ({"disturbance.shift_m": [0.06, 0.03]}, "disturbance.shift_m"),
    ({"disturbance.knock_push": -1}, "disturbance.knock_push"),
    ({"targets.fork.relative_to": "saucer"}, "targets.fork.relative_to"),
    ({"targets.fork.half_m": [0.0, 0.02]}, "targets.fork.half_m"),
])
def test_bad_task_config_names_the_key(overrides: dict, key: str) -> None:
    t = TASKS.get("rearrange-table").factory()
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        t.config(overrides)


def test_a_region_beside_a_missing_object_is_refused() -> None:
    t = TASKS.get("rearrange-table").factory()
    with pytest.raises(ConfigError, match=r"targets\.fork\.relative_to is 'cup'"):
        t.build(t.config({"targets.fork.relative_to": "cup"}), "none", 0)


@pytest.mark.parametrize("seed", [17, 18])
def test_the_cup_is_fitted_upright_and_one_hand_wide(seed: int) -> None:
    """Seed 18: the exact fit saw through 5.5 % of its surface at the thin rim (a pixel off into the cavity),
    was refused, and the raw cloud's diagonal span (12.5 cm) made the cup too wide for one hand."""
    t = TASKS.get("pour-dual").factory()
    world, _, hook, _ = t.build(t.config({}), "drop", seed)
    cup = TabletopRobot(world, hook=hook).observation(images=False).objects["cup"]
    truth = world.ground_truth().objects["cup"].pos
    world.close()
    assert cup.fit == "primitive" and cup.upright, cup.note
    assert max(cup.extent[1:]) < 0.095
    assert abs(cup.centroid[0] - truth[0]) < 0.002 and abs(cup.centroid[1] - truth[1]) < 0.002


def test_handover_block_dropped_into_the_region_then_touched_fails() -> None:
    """After the drop, the closed empty hand goes through a place onto the block that fell into the region and
    its pads touch it: a touch is no hold, so its letting go is no place (inner-monologue seed 13 at drop
    p 0.10 was scored a success that way)."""
    ok, d = _play("handover-block", lambda s: _let_go_over_the_region(s) + [
        {"action": "close_gripper", "arm": "right"},
        {"action": "place", "arm": "right", "x": 0.40, "y": -0.25},
        {"action": "back", "arm": "right"}])
    assert d["in_region"] and d["drops"] == 1, d
    assert not d["placed"] and not ok, d
