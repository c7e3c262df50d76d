"""System C's contact world: force-limited servos, two worlds that differ only in beliefs, conditions, tracking."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest

from kintsugi.core.errors import ConfigError, UnknownNameError
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import PickBoxConfig
from kintsugi.worlds.contact.objects import Physics
from kintsugi.worlds.contact.pick_box import TASK as PICK_BOX
from kintsugi.worlds.contact.robot import ContactRobot
from kintsugi.worlds.contact.world import EvaluationWorld, PlanningWorld, resolve


def _worlds(condition: str = "none", seed: int = 0):  # noqa: ANN202
    cfg = PickBoxConfig()
    setup = PICK_BOX.build(cfg, Drawer(condition, seed))
    return cfg, setup, EvaluationWorld(cfg, setup.scene, setup.truth), PlanningWorld(cfg, setup.scene, setup.nominal)


def test_effector_is_actuated_not_mocap_and_presses_with_at_most_its_force_limit() -> None:
    cfg, _, world, _ = _worlds()
    assert world.model.nmocap == 0 and world.model.nu == 5
    assert np.all(world.model.actuator_forcelimited[:5] == 1)
    robot = ContactRobot(world)
    x, y = -0.2, 0.1  # clear of the box
    robot.act(np.array([x, y, 0.05, 0.0, 0.0]), 1.0)
    obs = robot.act(np.array([x, y, 0.0, 0.0, 0.0]), 1.0)  # command the fingertips to the table top
    free_press = obs.force[2]
    obs = robot.act(np.array([x, y, -0.5, 0.0, 0.0]), 1.0)  # ... and far below it (clipped to the workspace)
    assert -cfg.effector.force_limit_n - 1.0 < obs.force[2] < free_press + 1e-6
    # a servo with a force range: the table pushes back with the force limit, not any force
    world.data.ctrl[2] = world.model.actuator_ctrlrange[2, 0]
    for _ in range(50):
        world.step(5)
    z_act = resolve(world.model, mujoco.mjtObj.mjOBJ_ACTUATOR, "z")
    assert abs(world.data.actuator_force[z_act]) <= cfg.effector.force_limit_n + 1e-9
    assert world.data.qpos[world.layout.ee_qpos[2]] > -0.003  # resting on the table, not through it


def test_tared_force_is_zero_in_free_air_and_opposes_a_push() -> None:
    _, setup, world, _ = _worlds()
    robot = ContactRobot(world)
    obs = robot.act(np.array([-0.2, 0.0, 0.1, 0.0, 0.1]), 1.5)
    assert np.linalg.norm(obs.force) < 0.3, obs.force
    box = obs.objects["box"].pos
    half_x = setup.scene.geometry["box"].parts[0].half[0]
    robot.act(np.array([box[0] - half_x - 0.05, box[1], 0.01, 0.0, 0.0]), 1.5)
    obs = robot.act(np.array([box[0] + 0.1, box[1], 0.01, 0.0, 0.0]), 0.1)  # shove the box along +x
    assert obs.force[0] > 0.5, obs.force
    assert world.pusher_force("box")[0] == pytest.approx(obs.force[0], abs=1.0)  # the truth agrees
    assert obs.objects["box"].pos[0] > box[0] + 0.005


def test_planning_world_shares_structure_and_holds_only_beliefs() -> None:
    _, setup, world, planning = _worlds("random", 3)
    assert planning.model.nq == world.model.nq and planning.model.nu == world.model.nu
    assert planning.layout.obj_qpos == world.layout.obj_qpos
    assert world.physics_of("box").mass_kg == pytest.approx(setup.truth["box"].mass_kg, rel=1e-5)
    assert planning.physics_of("box").mass_kg == pytest.approx(setup.nominal["box"].mass_kg, rel=1e-5)
    inertia = planning.model.body_inertia[planning.layout.obj_body["box"]].copy()
    planning.set_beliefs({"box": Physics(mass_kg=2.0 * setup.nominal["box"].mass_kg, friction=0.9)})
    assert planning.physics_of("box").friction == pytest.approx(0.9)
    assert np.allclose(planning.model.body_inertia[planning.layout.obj_body["box"]], 2 * inertia)
    assert planning.model.opt.timestep == pytest.approx(PickBoxConfig().sim.planning_timestep_s)
    assert world.model.opt.timestep == pytest.approx(PickBoxConfig().sim.timestep_s)


def test_conditions_draw_in_a_fixed_order_and_none_is_nominal() -> None:
    cfg = PickBoxConfig()
    none = PICK_BOX.build(cfg, Drawer("none", 4)).params
    assert none == PICK_BOX.build(cfg, Drawer("none", 9)).params
    assert none["box.mass_kg"] == pytest.approx(sum(cfg.box.mass_kg) / 2)
    pose, phys, rand = (PICK_BOX.build(cfg, Drawer(c, 4)).params for c in ("pose", "physics", "random"))
    assert pose["box.x_m"] == rand["box.x_m"] != none["box.x_m"]
    assert pose["box.mass_kg"] == none["box.mass_kg"]
    assert phys["box.mass_kg"] == rand["box.mass_kg"] != none["box.mass_kg"]
    with pytest.raises(ConfigError, match="unknown condition 'storm'.*random"):
        Drawer("storm", 0)


def test_names_are_resolved_with_the_known_ones_listed() -> None:
    _, _, world, _ = _worlds()
    with pytest.raises(UnknownNameError, match="finger_l"):
        resolve(world.model, mujoco.mjtObj.mjOBJ_BODY, "thumb")


def test_restart_puts_the_scene_back_and_keeps_the_clock() -> None:
    _, _, world, _ = _worlds()
    robot = ContactRobot(world)
    start = robot.observe()
    robot.act(np.array([0.1, 0.1, 0.2, 0.5, 0.05]), 0.5)
    obs = robot.restart()
    assert obs.t == pytest.approx(0.5) and robot.attempts == 2
    assert np.allclose(obs.ee, start.ee) and np.allclose(obs.objects["box"].pos, start.objects["box"].pos)


def test_object_sensors_report_the_tracked_body_frame_even_for_a_two_part_board() -> None:
    """Rollout costs and system identification compare sensor poses with the tracker's: both must be the
    body frame (the board's handle moves its centre of mass and turns its principal axes)."""
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS
    from kintsugi.worlds.contact.robot import pose_tracker

    load_builtins()
    task = TASKS.get("push-pick-board").factory()
    cfg = task.config({})
    world, _, _ = task.build(cfg, "random", 0)
    v = world.layout.obj_dof["board"]
    world.data.qvel[v:v + 6] = [0.1, -0.05, 0.02, 0.3, -0.2, 0.5]  # moving and spinning
    mujoco.mj_forward(world.model, world.data)
    tracked = pose_tracker(world)["board"]
    s = world.layout.sensors
    assert np.linalg.norm(world.model.body_ipos[world.model.body("board").id]) > 0.005  # the COM is off the origin
    np.testing.assert_allclose(world.data.sensordata[s["board_pos"]], tracked.pos, atol=1e-9)
    np.testing.assert_allclose(world.data.sensordata[s["board_quat"]], tracked.quat, atol=1e-9)
    np.testing.assert_allclose(world.data.sensordata[s["board_vel"]], tracked.lin_vel, atol=1e-9)
    world.close()
