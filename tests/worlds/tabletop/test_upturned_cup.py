"""A cup standing on its rim is not upright: the points of an upturned cup fit about as well with the opening up
(its closed bottom is a few of them), so perception checks the top for a closed disc and the opening becomes the
lower end; the `upright` check reads a container's opening as its top (pour-dual under `knock`: a cup stood up
on its rim passed the goal check)."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import pytest
from scipy.spatial.transform import Rotation

from kintsugi.methods.agentchord.observe import features
from kintsugi.taskgraph.constraints import Upright
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld


@pytest.fixture(scope="module")
def scene():  # noqa: ANN201
    world = TabletopWorld(TabletopConfig(), ["cup"], {"cup": StartPose(x=0.5, y=0.06)})
    yield world, TabletopRobot(world)
    world.close()


def _set(world: TabletopWorld, x: float, y: float, rpy: tuple[float, float, float]) -> None:
    """Test set-up only: drop the cup in a pose and let it come to rest."""
    m, d = world.model, world.data
    adr = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "cup")]
    q = Rotation.from_euler("xyz", rpy, degrees=True).as_quat()
    d.qpos[adr:adr + 7] = [x, y, 0.06, q[3], q[0], q[1], q[2]]
    d.qvel[:] = 0
    for _ in range(600):
        mujoco.mj_step(m, d)


@pytest.mark.parametrize("where", [(0.596, 0.062), (0.45, 0.0), (0.40, 0.15)])
def test_an_upturned_cup_is_not_upright_and_a_standing_one_is(scene, where) -> None:  # noqa: ANN001
    world, robot = scene
    check = Upright(object="cup", tol_deg=8.0)
    _set(world, *where, (180.0, 0.0, 0.0))
    f = robot.features(["cup"])["cup"]
    assert f.upright is False and f.extremes["opening"][2] < f.centroid[2]
    assert check.evaluate(features(robot, ["cup"])) > 0
    _set(world, *where, (0.0, 0.0, 0.0))
    f = robot.features(["cup"])["cup"]
    assert f.upright is True and f.extremes["opening"][2] > f.centroid[2]
    assert check.evaluate(features(robot, ["cup"])) < 0
