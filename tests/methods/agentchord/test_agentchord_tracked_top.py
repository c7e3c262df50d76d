"""The robot's tracked top in the checks: a bottle that fell mouth-first into the cup stands on its head with
its cap hidden, so the cameras alone read it upright (pour-single seed 49 was a false success). The conductor
knows which end is its top (`Tops`: encoders while held, continuity while falling) and hands that to the
checks as extreme `tracked_top`; `upright` and `tilted` then measure the tilt from the top. A seen cap, or a
container's seen opening, still wins over the tracked top: a cup stood up the wrong way round after it was knocked
over keeps a tracked top pointing up (pour-single under `all`, a false success)."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kintsugi.methods.agentchord.observe import with_tracked_top
from kintsugi.taskgraph.constraints import Tilted, Upright
from kintsugi.taskgraph.features import Features
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld

DOWN, UP = np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def on_its_head():  # noqa: ANN201
    """Perceived features of a bottle standing on its head (test set-up puts it there), and the same with
    its cap hidden from the cameras."""
    world = TabletopWorld(TabletopConfig(), ["bottle"], {"bottle": StartPose(x=0.42, y=-0.2)})
    m, d = world.model, world.data
    adr = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "bottle")]
    q = Rotation.from_euler("x", 180.0, degrees=True).as_quat()
    d.qpos[adr:adr + 7] = [0.42, -0.2, world.shapes["bottle"].half_height, q[3], q[0], q[1], q[2]]
    mujoco.mj_forward(m, d)
    seen = TabletopRobot(world).observation(images=False).objects["bottle"]
    world.close()
    hidden = seen.model_copy(update={"extremes": {k: v for k, v in seen.extremes.items() if k != "cap"},
                                     "upright": True})
    return seen, hidden


def _checks(f) -> tuple[float, float]:  # noqa: ANN001
    feats = Features(objects={"bottle": f})
    return (Upright(object="bottle", tol_deg=15).evaluate(feats),
            Tilted(object="bottle", min_deg=15).evaluate(feats))


def test_the_cameras_alone_read_a_capless_bottle_on_its_head_as_upright(on_its_head) -> None:
    _, hidden = on_its_head
    upright, tilted = _checks(hidden)
    assert upright <= 0.0 and tilted > 0.0  # the fooled reading this file is about


def test_the_tracked_top_turns_it_over(on_its_head) -> None:
    _, hidden = on_its_head
    f = with_tracked_top(hidden, DOWN)
    top = np.array(f.extremes["tracked_top"])
    assert top[2] < hidden.centroid[2] - 0.05  # the axis end on the tracked side, not an invented point
    upright, tilted = _checks(f)
    assert upright > 90.0  # upside down, not a near miss
    assert tilted < 0.0  # tilted 180 degrees: the lying branch (stand it up) takes it


def test_a_tracked_top_that_agrees_changes_nothing(on_its_head) -> None:
    _, hidden = on_its_head
    assert _checks(with_tracked_top(hidden, UP)) == pytest.approx(_checks(hidden))


def test_a_seen_cap_wins_over_the_tracked_top(on_its_head) -> None:
    seen, _ = on_its_head
    assert with_tracked_top(seen, UP) is seen  # nothing added where the cap is in sight
    assert _checks(seen)[0] > 90.0


def test_no_axis_or_no_estimate_adds_nothing(on_its_head) -> None:
    _, hidden = on_its_head
    assert with_tracked_top(hidden, None) is hidden
    axisless = hidden.model_copy(update={"axis": None})
    assert with_tracked_top(axisless, DOWN) is axisless


@pytest.fixture(scope="module")
def cup_on_its_rim():  # noqa: ANN201
    """Perceived features of a cup standing upside down (its opening on the table)."""
    world = TabletopWorld(TabletopConfig(), ["cup"], {"cup": StartPose(x=0.46, y=-0.03)})
    m, d = world.model, world.data
    adr = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "cup")]
    q = Rotation.from_euler("x", 180.0, degrees=True).as_quat()
    d.qpos[adr:adr + 3] = [0.46, -0.03, d.qpos[adr + 2]]
    d.qpos[adr + 3:adr + 7] = [q[3], q[0], q[1], q[2]]
    mujoco.mj_forward(m, d)
    seen = TabletopRobot(world).observation(images=False).objects["cup"]
    world.close()
    return seen


def test_a_seen_opening_wins_over_a_tracked_top_that_points_up(cup_on_its_rim) -> None:
    seen = cup_on_its_rim
    assert "opening" in seen.extremes and seen.extremes["opening"][2] < seen.centroid[2]
    fooled = with_tracked_top(seen, UP)
    assert "tracked_top" in fooled.extremes and fooled.extremes["tracked_top"][2] > seen.centroid[2]
    upright = Upright(object="cup", tol_deg=8).evaluate(Features(objects={"cup": fooled}))
    assert upright > 90.0  # on its rim, whatever the robot believed of its top
