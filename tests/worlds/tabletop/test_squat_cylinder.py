"""A cylinder about as long as it is wide (the coffee capsule, 36 mm across, 30 mm tall) lying on its side is
perceived lying: its cloud's principal axes tell nothing about its axis, so the fit also starts level. Lying in
the tray at some yaws it was fitted standing, and a capsule on its side passed the goal check (coffee-tray
under `knock`). The scorer counts an object whose two ends nothing tells apart as upright on either end."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import pytest
from scipy.spatial.transform import Rotation

from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.spec import end_free, upright
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld


@pytest.fixture(scope="module")
def scene():  # noqa: ANN201
    world = TabletopWorld(TabletopConfig(), ["capsule", "tray"],
                          {"capsule": StartPose(x=0.40, y=0.2), "tray": StartPose(x=0.56, y=0.0)})
    yield world, TabletopRobot(world)
    world.close()


def _drop(world: TabletopWorld, rpy: tuple[float, float, float]) -> None:
    """Test set-up only: let the capsule fall into the tray in a pose and come to rest."""
    m, d = world.model, world.data
    adr = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "capsule")]
    q = Rotation.from_euler("xyz", rpy, degrees=True).as_quat()
    d.qpos[adr:adr + 7] = [0.53, 0.0, 0.06, q[3], q[0], q[1], q[2]]
    d.qvel[:] = 0
    for _ in range(800):
        mujoco.mj_step(m, d)


@pytest.mark.parametrize("rpy", [(90, 0, 30), (0, 90, 60), (90, 0, 0), (0, 90, 0)])
def test_a_capsule_lying_in_the_tray_is_not_perceived_upright(scene, rpy) -> None:  # noqa: ANN001
    world, robot = scene
    _drop(world, rpy)
    assert world.ground_truth().objects["capsule"].tilt_deg > 80
    f = robot.features(["capsule"])["capsule"]
    assert f.upright is False and f.tilt_deg > 80


def test_a_standing_capsule_still_is(scene) -> None:  # noqa: ANN001
    world, robot = scene
    _drop(world, (0, 0, 30))
    f = robot.features(["capsule"])["capsule"]
    assert f.upright is True and f.tilt_deg < 2


def test_upright_on_either_end_only_without_a_top_to_tell(scene) -> None:  # noqa: ANN001
    world, _ = scene
    _drop(world, (180, 0, 0))
    truth = world.ground_truth()
    cap = shape_of("capsule", world.cfg.objects)
    assert end_free(cap) and upright(truth, "capsule", 10.0, cap)
    assert not upright(truth, "capsule", 10.0)  # without the shape: the body's own up
    assert not end_free(shape_of("bottle", world.cfg.objects))  # its painted cap marks the top
    assert not end_free(shape_of("cup", world.cfg.objects))  # its opening does
