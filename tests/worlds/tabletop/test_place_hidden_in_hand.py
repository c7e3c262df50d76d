"""A place of an object the cameras no longer see in the hand (a small capsule between the fingers) is planned
from how the hand took it, and sets it down standing where asked; once the hand has let go of it that way (an
opening, a fresh closing) the place needs to see it again. A real robot; the cameras are told to miss the held
object, everything else is as perceived."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import numpy as np
import pytest

from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld

START = {"bottle": StartPose(x=0.40, y=-0.25), "cup": StartPose(x=0.46, y=0.05)}
SPOT = (0.42, -0.15)


def _blind_to(robot: TabletopRobot, obj: str) -> None:
    """From now on perception reports `obj` as hidden (as few points as a capsule in the fingers shows)."""
    see = robot._perception.features

    def features(names=None):  # noqa: ANN001, ANN202
        out = see(names)
        if obj in out:
            out[obj] = out[obj].model_copy(update={"visible": False, "centroid": None, "note": "hidden in the hand"})
        return out
    robot._perception.features = features


@pytest.fixture()
def held() -> tuple[TabletopWorld, TabletopRobot]:
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    robot = TabletopRobot(world)
    assert robot.execute({"action": "grasp", "arm": "right", "obj": "bottle"}).reached
    assert robot.execute({"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.06)}).reached
    _blind_to(robot, "bottle")
    yield world, robot
    world.close()


def test_a_hidden_held_object_is_placed_as_the_hand_took_it(held) -> None:  # noqa: ANN001
    world, robot = held
    result = robot.execute({"action": "place", "arm": "right", "x": SPOT[0], "y": SPOT[1]})
    assert result.planned and not result.unseen, result.message
    truth = world.ground_truth().objects["bottle"]  # read by the test only
    assert np.hypot(truth.pos[0] - SPOT[0], truth.pos[1] - SPOT[1]) < 0.02
    assert truth.tilt_deg < 10.0


def test_after_the_hand_closes_again_the_place_must_see_it(held) -> None:  # noqa: ANN001
    world, robot = held
    robot.execute({"action": "close_gripper", "arm": "right"})
    result = robot.execute({"action": "place", "arm": "right", "x": SPOT[0], "y": SPOT[1]})
    assert not result.planned and result.unseen, result.message
