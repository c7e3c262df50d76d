"""The bottle's painted cap: the one cue that tells its top from its bottom.

A plain cylinder looks the same either way up, so a stand-up could set a bottle down on its head and every
check would pass it (pour-single seeds 40 and 49 were false successes). The cap is paint: no mass, no
contact. Perception reports where it is seen (extreme `cap`); an object on its head is then not upright, and
the conductor's top estimate follows the cap outright.
"""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kintsugi.core.config import apply_overrides
from kintsugi.methods.agentchord.tops import Tops
from kintsugi.taskgraph.constraints import Upright
from kintsugi.taskgraph.features import Features
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld

POSES = {  # body rotation (extrinsic xyz degrees) -> where the top points
    "upright": ((0.0, 0.0, 0.0), (0, 0, 1)),
    "on its head": ((180.0, 0.0, 0.0), (0, 0, -1)),
    "lying, top +y": ((-90.0, 0.0, 0.0), (0, 1, 0)),
    "lying, top -y": ((90.0, 0.0, 0.0), (0, -1, 0)),
    "lying, top +x": ((0.0, 90.0, 0.0), (1, 0, 0)),
}


def _pose(world: TabletopWorld, rpy: tuple[float, float, float]) -> None:
    """Test set-up only: put the bottle in a pose, resting on the table (its radius or half height up)."""
    m, d = world.model, world.data
    adr = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "bottle")]
    r, hh = world.shapes["bottle"].radius, world.shapes["bottle"].half_height
    up = abs(rpy[0]) + abs(rpy[1])
    z = hh if up in (0.0, 180.0) else r
    q = Rotation.from_euler("xyz", rpy, degrees=True).as_quat()  # x y z w
    d.qpos[adr:adr + 7] = [0.42, -0.2, z, q[3], q[0], q[1], q[2]]
    mujoco.mj_forward(m, d)


@pytest.fixture(scope="module", params=["perceived", "truth"])
def scene(request):  # noqa: ANN001, ANN201
    cfg = apply_overrides(TabletopConfig(), {"perception.objects": request.param})
    world = TabletopWorld(cfg, ["bottle"], {"bottle": StartPose(x=0.42, y=-0.2)})
    yield world, TabletopRobot(world)
    world.close()


@pytest.mark.parametrize("pose", POSES)
def test_the_cap_shows_the_top_and_a_bottle_on_its_head_is_not_upright(scene, pose: str) -> None:
    world, robot = scene
    rpy, top = POSES[pose]
    _pose(world, rpy)
    f = robot.observation(images=False).objects["bottle"]
    cap, centre = np.array(f.extremes["cap"]), np.array(f.centroid)
    assert float((cap - centre) @ np.array(top)) > 0.05  # the cap is seen at the top end
    assert f.upright is (pose == "upright")
    check = Upright(object="bottle", tol_deg=15).evaluate(Features(objects={"bottle": f}))
    assert (check <= 0.0) is (pose == "upright")
    if pose == "on its head":
        assert check > 90.0  # not a near miss: upside down
    tops = Tops()
    tops.world["bottle"] = -np.array(top, float)  # a wrong estimate (the sign lost in a fall) ...
    tops.observe({"bottle": f})
    assert tops.world["bottle"] @ np.array(top) > 0.9  # ... is put right by the seen cap


def test_the_cap_is_paint_no_mass_no_contact(scene) -> None:
    world, _ = scene
    m = world.model
    cap = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "bottle_cap")
    body = m.geom_bodyid[cap]
    assert m.geom_contype[cap] == 0 and m.geom_conaffinity[cap] == 0
    assert m.body_mass[body] == pytest.approx(world.cfg.objects.bottle.mass_kg)
    # the object's primitive is unchanged: the cap stands 0.5 mm proud of the body and no higher
    r, hh = world.shapes["bottle"].radius, world.shapes["bottle"].half_height
    assert m.geom_size[cap][0] == pytest.approx(r + 0.0005) and m.geom_pos[cap][2] + m.geom_size[cap][1] == \
        pytest.approx(hh + 0.0005)
