"""A lying object no arm can grasp is pushed back into reach and grasped; a push that cannot help is a recorded
failure with its reason. The conductor's reach handling (`Reaching`, `Pushing`) on a real tabletop scene: the
object is laid where no grasp of it is within reach, and the conductor sees it only through perception."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
from types import SimpleNamespace

import numpy as np
import pytest

from kintsugi.core.config import apply_overrides
from kintsugi.methods.agentchord import pushing
from kintsugi.methods.agentchord.pushing import Pushing
from kintsugi.methods.agentchord.reaching import Reaching
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld
from tests.worlds.tabletop.test_tabletop_push import START, lay

EDGE = SimpleNamespace(id="e_take", target="n1")
FAR = (0.72, -0.36)
"""A lying object here is 0.77 m from the right arm's base: no grasp of it (nor the drag) is within either arm's
reach, and its far side is past the workspace's far edge (the push presses on its top)."""


class Log:
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def event(self, t: float, kind: str, detail: str) -> None:
        self.events.append((kind, detail))


class Hands(Reaching, Pushing):
    """The conductor's reach handling over a real robot: actions run as asked, a wait reads until still."""

    def __init__(self, robot: TabletopRobot, arms: set[str]) -> None:
        self.robot, self.arms, self.log = robot, arms, Log()
        self.graph = SimpleNamespace(node=lambda _: SimpleNamespace(constraints=[]))

    def _execute(self, edge, name: str, args: dict, unplanned_ok: bool = False) -> bool:  # noqa: ANN001
        return bool(self.robot.execute({"action": name, **args}).planned)

    def wait_still(self, arm: str, objs: set[str], edge) -> bool:  # noqa: ANN001
        for _ in range(20):
            a = self.robot.features(objs)
            self.robot.execute({"action": "open_gripper", "arm": arm})
            b = self.robot.features(objs)
            if all(np.linalg.norm(np.subtract(a[k].centroid, b[k].centroid)) < 3e-4 for k in objs):
                return True
        return False


def _scene(cfg: TabletopConfig, obj: str = "bottle") -> tuple[TabletopWorld, TabletopRobot]:
    world = TabletopWorld(cfg, ["bottle", "cup"], START)
    lay(world, obj, *FAR)
    return world, TabletopRobot(world)


def _take(hands: Hands, obj: str = "bottle") -> tuple:
    call = {"action": "grasp", "arm": "right", "obj": obj}
    result = hands.robot.execute(call)
    assert result.ik_failed, f"the scene must start with the {obj} out of the grasp's reach"
    return hands.reach_otherwise(EDGE, call, result)


def test_an_object_out_of_reach_is_pushed_back_and_grasped() -> None:
    world, robot = _scene(TabletopConfig())
    try:
        hands = Hands(robot, {"left", "right"})
        result, call = _take(hands)
        pushes = [d for k, d in hands.log.events if k == "push into reach"]
        assert pushes and "pushes it" in pushes[0] and "within the right arm's grasp" in pushes[-1], hands.log.events
        assert result.planned and not result.ik_failed, result.message
        assert world.pad_contacts("right")[0].get("bottle") == 2  # both pads on it: grasped
        moved = world.ground_truth().objects["bottle"].pos  # where the push left it (read by the test only)
        assert moved[0] < FAR[0] - 0.02
    finally:
        world.close()


def test_a_push_that_cannot_move_it_ends_after_a_bounded_number_of_tries(monkeypatch) -> None:
    """A bottle too heavy for the hand to move: every push leaves it out of reach, and after MAX_PUSHES the action
    fails with the reason recorded (the conductor then ends the trial as a recorded failure or re-plans)."""
    monkeypatch.setattr(pushing, "MAX_PUSHES", 1)
    world, robot = _scene(apply_overrides(TabletopConfig(), {"objects.bottle.mass_kg": 60.0}))
    try:
        hands = Hands(robot, {"right"})
        result, _ = _take(hands)
        assert result.ik_failed and not result.planned
        pushes = [d for k, d in hands.log.events if k == "push into reach"]
        assert sum("pushes it" in d for d in pushes) == 1
        assert "still out of every arm's grasp after 1 push;" in pushes[-1]
    finally:
        world.close()


def test_no_push_within_reach_is_a_recorded_reason_and_nothing_moves() -> None:
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    try:
        lay(world, "cup", 0.78, 0.0)  # 0.89 m from either base, at the table's far edge
        robot = TabletopRobot(world)
        hands = Hands(robot, {"left", "right"})
        q0 = {a: world.joint_targets(a).copy() for a in ("left", "right")}
        result, _ = _take(hands, "cup")
        assert result.ik_failed
        assert any(k == "push into reach" and "no push of it is within reach" in d for k, d in hands.log.events)
        assert all(np.allclose(world.joint_targets(a), q0[a]) for a in ("left", "right"))
    finally:
        world.close()


def test_no_push_when_the_other_arm_grasps_it() -> None:
    """The other arm reaches it: no push (a re-plan gives the grasp to that arm)."""
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    try:
        lay(world, "cup", 0.55, -0.35)
        robot = TabletopRobot(world)
        hands = Hands(robot, {"left", "right"})
        call = {"action": "grasp", "arm": "left", "obj": "cup"}
        result = robot.execute(call)
        assert result.ik_failed
        hands.reach_otherwise(EDGE, call, result)
        assert not any(k == "push into reach" for k, _ in hands.log.events)
    finally:
        world.close()


@pytest.mark.parametrize("arms", [{"left"}])
def test_only_the_plans_arms_push(arms: set[str]) -> None:
    """An instruction that names one arm: the other never pushes (here none of the plan's arms reaches)."""
    world, robot = _scene(TabletopConfig())
    try:
        hands = Hands(robot, arms)
        call = {"action": "grasp", "arm": "left", "obj": "cup"}
        result = robot.execute(call)
        hands.reach_otherwise(EDGE, call, result)
        assert not any("the right hand" in d for _, d in hands.log.events)
    finally:
        world.close()
