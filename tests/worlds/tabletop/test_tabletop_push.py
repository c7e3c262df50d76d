"""The `push` action: the closed hand moves an object by contact (no teleporting), planned before anything moves."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import math

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kintsugi.worlds.tabletop.actions import ActionError
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.pushing import contact_tip, reach_along
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld

START = {"bottle": StartPose(x=0.30, y=0.25), "cup": StartPose(x=0.46, y=0.0)}


def lay(world: TabletopWorld, name: str, x: float, y: float, yaw_deg: float = 90.0) -> None:
    """Lay the object on its side at (x, y), its axis along `yaw_deg`, and let it come to rest (the scene's set-up)."""
    a = world._obj_qpos[name]
    q = Rotation.from_euler("ZY", [math.radians(yaw_deg), math.pi / 2]).as_quat()
    world.data.qpos[a:a + 3] = (x, y, 0.05)
    world.data.qpos[a + 3:a + 7] = (q[3], q[0], q[1], q[2])
    world.data.qvel[:] = 0.0
    mujoco.mj_forward(world.model, world.data)
    for _ in range(60):
        world.tick()


@pytest.fixture()
def scene() -> tuple[TabletopWorld, TabletopRobot]:
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    yield world, TabletopRobot(world)
    world.close()


def test_a_push_moves_a_lying_cup_by_contact_towards_the_robot(scene) -> None:
    world, robot = scene
    lay(world, "cup", 0.62, -0.32)
    before, steps0 = np.array(world.ground_truth().objects["cup"].pos), world.steps
    r = robot.execute({"action": "push", "arm": "right", "obj": "cup", "dxy": [-0.12, 0.0]})
    assert r.planned and not r.ik_failed, r.message
    for _ in range(100):
        world.tick()
    after = np.array(world.ground_truth().objects["cup"].pos)
    assert world.steps - steps0 > 100  # the hand moved it over many control steps, nothing was set
    assert -0.15 <= after[0] - before[0] <= -0.06 and abs(after[1] - before[1]) < 0.05


def test_a_push_beyond_the_workspace_is_refused_and_nothing_moves(scene) -> None:
    world, robot = scene
    lay(world, "cup", 0.74, 0.0)
    q0, steps0 = world.joint_targets("right").copy(), world.steps
    r = robot.execute({"action": "push", "arm": "right", "obj": "cup", "dxy": [-0.12, 0.0], "contact_deg": 90.0})
    planned = robot.execute({"action": "push", "arm": "right", "obj": "cup", "dxy": [-0.12, 0.0]}, plan_only=True)
    assert not r.planned or r.clipped
    assert not planned.planned or planned.clipped  # the start behind the cup is past the workspace's far edge
    if not r.planned:
        assert world.steps == steps0 and np.allclose(world.joint_targets("right"), q0)


def test_push_arguments_are_validated() -> None:
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    try:
        robot = TabletopRobot(world)
        with pytest.raises(ActionError, match="contact_deg"):
            robot.execute({"action": "push", "arm": "right", "obj": "cup", "dxy": [0.1, 0.0], "contact_deg": 120})
        with pytest.raises(ActionError, match="unknown object"):
            robot.execute({"action": "push", "arm": "right", "obj": "plate", "dxy": [0.1, 0.0]})
    finally:
        world.close()


def test_the_push_starts_behind_the_object_from_its_perceived_extent(scene) -> None:
    world, robot = scene
    lay(world, "cup", 0.55, -0.30, yaw_deg=0.0)  # its axis along x: it reaches half its length that way
    f = robot.features({"cup"})["cup"]
    u = np.array([-1.0, 0.0])
    assert reach_along(f, u) == pytest.approx(0.045, abs=0.012)  # the cup's half height (0.045) along its axis
    side, top = contact_tip(f, u, 90.0), contact_tip(f, u, 0.0)
    assert side[0] > f.centroid[0] + reach_along(f, u) and side[2] < f.centroid[2]  # behind it, low
    assert top[0] == pytest.approx(f.centroid[0]) and top[2] > f.centroid[2]  # on its top
