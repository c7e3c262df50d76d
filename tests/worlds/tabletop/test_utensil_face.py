"""A utensil lying flat counts as flat on either face: its handle and head are slabs, the same turned over, and the
instruction asks for flat: scoring a turned-over spoon as not flat would judge what nothing, the robot's sensors
included, can tell apart. On its edge it is not flat; turned end for end its head points the other way, which the
heading check still catches."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import pytest
from scipy.spatial.transform import Rotation

from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.spec import end_free, rest_level
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld


@pytest.fixture(scope="module")
def world():  # noqa: ANN201
    w = TabletopWorld(TabletopConfig(), ["plate", "fork", "spoon"],
                      {"plate": StartPose(x=0.45, y=0.0), "fork": StartPose(x=0.30, y=0.25),
                       "spoon": StartPose(x=0.30, y=-0.25)})
    yield w
    w.close()


def _lay(w: TabletopWorld, rpy: tuple[float, float, float]) -> None:
    """Test set-up only: lay the spoon in a pose and let it come to rest."""
    m, d = w.model, w.data
    adr = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "spoon")]
    q = Rotation.from_euler("xyz", rpy, degrees=True).as_quat()
    d.qpos[adr:adr + 7] = [0.30, -0.25, 0.03, q[3], q[0], q[1], q[2]]
    d.qvel[:] = 0
    for _ in range(600):
        mujoco.mj_step(m, d)


@pytest.mark.parametrize(("rpy", "flat"), [((0, 0, 0), True), ((180, 0, 0), True), ((90, 0, 0), False)])
def test_a_spoon_is_flat_on_either_face_and_not_on_its_edge(world, rpy, flat: bool) -> None:  # noqa: ANN001
    _lay(world, rpy)
    sh = shape_of("spoon", world.cfg.objects)
    assert end_free(sh)
    truth = world.ground_truth()
    assert rest_level(truth, "spoon", sh.rest_height, 10.0, shape=sh) is flat
    assert rest_level(truth, "spoon", sh.rest_height, 10.0) is (flat and rpy == (0, 0, 0))  # without the shape
