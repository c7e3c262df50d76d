"""Tabletop physics: friction grasps hold through a lift and a 90 deg pour, too weak a grasp slips,
a drop disturbance really drops, and none of it raises a MuJoCo warning or a NaN."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest

from kintsugi.core.config import apply_overrides
from kintsugi.worlds.tabletop.conditions import DropDisturbance
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld
from tests.sim_checks import assert_no_warnings

START = {"bottle": StartPose(x=0.40, y=-0.25)}
GRASP = {"action": "grasp", "arm": "right", "obj": "bottle"}
LIFT = {"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.15)}
POUR = {"action": "rotate_eef", "arm": "right", "angle_deg": -90.0}


def _world(**overrides: object) -> tuple[TabletopWorld, TabletopRobot]:
    cfg = apply_overrides(TabletopConfig(), {k.replace("__", "."): v for k, v in overrides.items()})
    world = TabletopWorld(cfg, ["bottle"], START)
    return world, TabletopRobot(world)


def _in_hand(world: TabletopWorld) -> tuple[np.ndarray, np.ndarray]:
    """Bottle position and axis in the gripper frame."""
    pos, rot = world.tcp_pose("right")
    b = world.bodies["bottle"]
    return rot.T @ (world.data.xpos[b] - pos), rot.T @ world.data.xmat[b].reshape(3, 3)[:, 2]


@pytest.fixture(scope="module")
def poured() -> dict[str, object]:
    world, robot = _world()
    out: dict[str, object] = {"grasp": robot.execute(GRASP)}
    out["touch"] = world.pad_contacts("right")[0]
    p0, a0 = _in_hand(world)
    z0 = world.data.xpos[world.bodies["bottle"]][2]
    out["lift"] = robot.execute(LIFT)
    out["lift_slip"] = _in_hand(world)[0] - p0
    out["rise"] = world.data.xpos[world.bodies["bottle"]][2] - z0
    out["pour"] = robot.execute(POUR)
    p, a = _in_hand(world)
    out["pour_slip"] = p - p0
    out["pour_axis_deg"] = float(np.degrees(np.arccos(np.clip(a @ a0, -1, 1))))
    out["tilt_deg"] = world.ground_truth().objects["bottle"].tilt_deg
    out["held"] = world.ground_truth().held["right"]
    out["world"] = world
    world.close()
    return out


def test_grasp_closes_on_the_bottle_with_both_pads(poured: dict) -> None:
    assert poured["grasp"].reached, poured["grasp"]
    assert poured["touch"] == {"bottle": 2}


def test_held_bottle_survives_a_lift(poured: dict) -> None:
    assert poured["lift"].reached
    assert poured["rise"] == pytest.approx(0.15, abs=0.005)
    assert np.linalg.norm(poured["lift_slip"]) < 0.003, poured["lift_slip"]


def test_held_bottle_survives_a_90_degree_pour(poured: dict) -> None:
    assert poured["pour"].reached
    assert poured["tilt_deg"] == pytest.approx(90.0, abs=3.0)
    assert np.linalg.norm(poured["pour_slip"]) < 0.003, poured["pour_slip"]
    assert poured["pour_axis_deg"] < 2.0  # the bottle's axis did not turn in the fingers
    assert poured["held"] == ["bottle"]
    assert_no_warnings(poured["world"])


def test_too_weak_a_grasp_slips() -> None:
    # 1 N per finger: 2 x 1.5 x 1 N of friction cannot carry a 0.4 kg bottle. Ground-truth features
    # centre the grasp exactly, so both pads do touch before the lift (a real squeeze, not a miss).
    world, robot = _world(robot__grip_force_n=1.0, motion__gripper_time_s=2.0, perception__objects="truth")
    robot.execute(GRASP)
    assert world.pad_contacts("right")[0] == {"bottle": 2}
    z0 = world.data.xpos[world.bodies["bottle"]][2]
    robot.execute(LIFT)
    assert world.data.xpos[world.bodies["bottle"]][2] - z0 < 0.02
    assert world.ground_truth().held["right"] == []
    assert_no_warnings(world)
    world.close()


def test_drop_disturbance_drops_the_held_bottle() -> None:
    world, _ = _world()
    drop = DropDisturbance(world, p=1.0, release_s=0.3, seed=0)
    world.watchers.append(drop)
    robot = TabletopRobot(world, hook=drop)
    robot.execute(GRASP)  # the hook fires during the grasp too, but nothing is held yet
    assert drop.events == []
    robot.execute(LIFT)
    assert drop.events and "dropped bottle" in drop.events[0][1]
    for _ in range(60):  # let it land
        world.tick()
    truth = world.ground_truth()
    assert truth.held["right"] == []
    assert truth.objects["bottle"].pos[2] < 0.11  # back on the table (standing or fallen)
    assert robot.observation(images=False).arms["right"].gripper_closed  # the robot still thinks it holds it
    assert_no_warnings(world)
    world.close()


@pytest.mark.parametrize("kind", ["block", "tray", "fork", "bottle"])
def test_a_dropped_object_never_gains_energy(kind: str) -> None:
    """A falling, spinning object meets the table: the world's total mechanical energy (MuJoCo's
    own potential + kinetic) must never rise above where it started. With a 1 mm impedance width a
    corner landing at 2 m/s gained up to 40x its fall energy (handover's block left the table)."""
    from scipy.spatial.transform import Rotation

    world = TabletopWorld(TabletopConfig(), [kind], {kind: StartPose(x=0.4, y=0.0)})
    m, d = world.model, world.data
    m.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    a, v = world._obj_qpos[kind], world._obj_dof[kind]
    home_qpos, home_ctrl = d.qpos.copy(), d.ctrl.copy()  # arms at home, out of the way
    rng = np.random.default_rng(0)
    worst = 0.0
    for k in range(30):
        mujoco.mj_resetData(m, d)
        d.qpos[:], d.ctrl[:] = home_qpos, home_ctrl
        x, y, z, w = Rotation.random(random_state=k).as_quat()
        d.qpos[a:a + 7] = (0.4, 0.0, 0.2, w, x, y, z)
        d.qvel[v:v + 6] = (0.0, 0.0, -2.0, *rng.normal(0.0, 5.0, 3))
        energy = []
        for _ in range(500):
            mujoco.mj_step(m, d)
            mujoco.mj_forward(m, d)
            energy.append(d.energy.sum())
        rest = energy[-1]  # settled on the table
        worst = max(worst, (max(energy) - rest) / (energy[0] - rest))
    world.close()
    assert worst <= 1.02, f"{kind} left a landing with {worst:.2f}x the energy it fell with"
