"""The shift and knock disturbances act on the physics: the target really slides by the drawn
distance, a knocked bottle or capsule really falls, and neither touches what a gripper holds."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import numpy as np
import pytest

from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.disturbances import Disturbances, KnockDisturbance, ShiftDisturbance
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld
from tests.sim_checks import assert_no_warnings

LAYOUT = {"bottle": StartPose(x=0.40, y=-0.25), "cup": StartPose(x=0.46, y=0.0),
          "capsule": StartPose(x=0.38, y=0.22)}


def _world(objects: tuple[str, ...]) -> TabletopWorld:
    return TabletopWorld(TabletopConfig(), objects, {k: LAYOUT[k] for k in objects})


def _settle(world: TabletopWorld, seconds: float) -> None:
    for _ in range(round(seconds / world.cfg.sim.control_dt_s)):
        world.tick()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_shift_slides_the_cup_by_the_drawn_distance(seed: int) -> None:
    world = _world(("bottle", "cup"))
    shift = ShiftDisturbance(world, "cup", (0, 0), world.cfg.disturbance, seed)
    world.watchers.append(shift)
    start = world.ground_truth().objects["cup"].pos
    shift.begin_action(1.0, ("right",))
    _settle(world, 1.5)
    end = world.ground_truth().objects["cup"]
    moved = float(np.hypot(end.pos[0] - start[0], end.pos[1] - start[1]))
    lo, hi = world.cfg.disturbance.shift_m
    assert lo <= shift.distance <= hi
    assert moved == pytest.approx(shift.distance, abs=0.004)
    assert end.tilt_deg < 2.0 and end.speed_m_s < 0.01  # slid, not tipped or flung
    assert shift.events and "cup slid" in shift.events[0][1]
    assert_no_warnings(world)
    world.close()


@pytest.mark.parametrize(("obj", "others"), [("bottle", ("cup",)), ("capsule", ())])
def test_knock_tips_a_standing_object_over(obj: str, others: tuple[str, ...]) -> None:
    world = _world((obj, *others))
    knock = KnockDisturbance(world, obj, (0, 0), world.cfg.disturbance, seed=4)
    world.watchers.append(knock)
    assert world.ground_truth().objects[obj].tilt_deg < 1.0
    knock.begin_action(0.5, ("right",))
    _settle(world, 2.0)
    fallen = world.ground_truth().objects[obj]
    assert fallen.tilt_deg > 60.0, fallen
    assert fallen.speed_m_s < 0.05
    assert knock.events and "knocked" in knock.events[0][1]
    assert not world.data.xfrc_applied.any()  # the push ended
    assert_no_warnings(world)
    world.close()


def test_a_knock_never_acts_on_a_held_object() -> None:
    world = _world(("bottle",))
    knock = KnockDisturbance(world, "bottle", (1, 1), world.cfg.disturbance, seed=0)  # during the 2nd action
    hook = Disturbances([knock])
    world.watchers.append(hook)
    robot = TabletopRobot(world, hook=hook)
    robot.execute({"action": "grasp", "arm": "right", "obj": "bottle"})
    robot.execute({"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.1)})
    assert knock.fired and "skipped" in hook.events[0][1]
    truth = world.ground_truth()
    assert truth.held["right"] == ["bottle"] and truth.objects["bottle"].tilt_deg < 5.0
    world.close()


def test_disturbance_draws_do_not_depend_on_the_other_disturbances() -> None:
    # Paired trials: the shift of seed s is the same whether or not a knock or a drop also runs.
    world = _world(("bottle", "cup"))
    a = ShiftDisturbance(world, "cup", (0, 2), world.cfg.disturbance, seed=9)
    KnockDisturbance(world, "bottle", (0, 0), world.cfg.disturbance, seed=9)
    b = ShiftDisturbance(world, "cup", (0, 2), world.cfg.disturbance, seed=9)
    c = ShiftDisturbance(world, "cup", (0, 2), world.cfg.disturbance, seed=10)
    assert a.distance == b.distance and a._fire_in == b._fire_in
    assert a.distance != c.distance
    world.close()


def test_a_drop_draws_only_for_actions_that_start_with_an_object_in_hand() -> None:
    """The k-th carrying action of every method meets the same draws: empty-handed actions (waits, trips home,
    whose number differs between methods) draw nothing, so they cannot shift the later draws."""
    from kintsugi.worlds.tabletop.conditions import DropDisturbance

    world = _world(("bottle",))
    quiet, busy = DropDisturbance(world, 1.0, 0.3, seed=3), DropDisturbance(world, 1.0, 0.3, seed=3)
    for _ in range(5):  # nothing in hand: no draws, nothing pending
        busy.begin_action(1.0, ("right",))
        assert busy._pending is None
    robot = TabletopRobot(world)
    assert robot.execute({"action": "grasp", "arm": "right", "obj": "bottle"}).reached
    assert "bottle" in world.pad_contacts("right")[0]
    quiet.begin_action(1.0, ("right",))
    busy.begin_action(1.0, ("right",))
    assert busy._pending is not None and busy._pending == quiet._pending  # p = 1: a drop, at the same instant
    assert busy._rng.random() == quiet._rng.random()  # same draws consumed
    world.close()
