"""Ground-truth scoring of the contact tasks on real physics, driven by plain servo commands (no planner)."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest

from kintsugi.core.plugins import load_builtins

from kintsugi.core.registry import TASKS
from kintsugi.worlds.contact.robot import ContactRobot

load_builtins()


def _task(name: str, condition: str = "none", seed: int = 0, **over):  # noqa: ANN003, ANN202
    task = TASKS.get(name).factory()
    cfg = task.config(over)
    world, scorer, setup = task.build(cfg, condition, seed)
    return cfg, world, scorer, setup


def _press(force_n: float, seconds: float):  # noqa: ANN202
    """Push the box to the wall by hand-written servo targets, then hold a command worth `force_n`."""
    cfg, world, scorer, setup = _task("push-force")
    robot = ContactRobot(world, watchers=[scorer.watch])
    box = robot.observe().objects["box"].pos
    hx = setup.scene.geometry["box"].parts[0].half[0]
    robot.act(np.array([box[0] - hx - 0.04, box[1], 0.05, 0, 0]), 0.8)
    robot.act(np.array([box[0] - hx - 0.04, box[1], 0.008, 0, 0]), 0.5)
    for x in np.linspace(box[0] - hx - 0.01, 0.13, 30):
        robot.act(np.array([x, box[1], 0.008, 0, 0]), 0.05)
    hand = robot.act(np.array([0.125, box[1], 0.008, 0, 0]), 0.5).ee[0]
    robot.act(np.array([hand + force_n / cfg.effector.kp_n_per_m, box[1], 0.008, 0, 0]), seconds)
    return scorer.finish(world)


def test_push_force_counts_only_an_unbroken_stretch_in_the_band() -> None:
    ok, details = _press(5.0, 2.6)
    assert ok and details.longest_in_band_s >= 2.0 and abs(details.mean_force_n - 5.0) < 1.0
    assert details.gap_to_wall_m < 0.003
    ok, details = _press(5.0, 1.2)  # the right force, not long enough
    assert not ok and 1.0 < details.longest_in_band_s < 2.0
    ok, details = _press(12.0, 2.6)  # long enough, too hard
    assert not ok and details.longest_in_band_s < 0.5 and details.max_force_n > 10


def _teleport(world, name: str, xy: tuple[float, float]) -> None:  # noqa: ANN001
    a = world.layout.obj_qpos[name]
    world.data.qpos[a:a + 2] = xy
    world.data.qvel[world.layout.obj_dof[name]:world.layout.obj_dof[name] + 6] = 0
    mujoco.mj_forward(world.model, world.data)
    world.step(200)


def test_pick_clutter_wants_the_box_on_the_goal_and_the_clutter_undisturbed() -> None:
    cfg, world, scorer, _ = _task("pick-clutter")
    ok, details = scorer.finish(world)
    assert not ok and details.goal_distance_m > 0.1
    _teleport(world, "box", cfg.clutter.goal_m)
    ok, details = scorer.finish(world)
    assert ok, details
    _teleport(world, "clutter_0", (-0.25, -0.2))  # shoved away
    ok, details = scorer.finish(world)
    assert not ok and details.max_disturb_m > cfg.scoring.max_disturb_m


def test_clutter_sits_round_the_box_without_touching_it() -> None:
    for seed in range(5):
        _, world, _, setup = _task("pick-clutter", "random", seed)
        world.step(100)
        names = {mujoco.mj_id2name(world.model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) for g in world.layout.obj_geoms["box"]}
        for i in range(world.data.ncon):
            c = world.data.contact[i]
            pair = {mujoco.mj_id2name(world.model, mujoco.mjtObj.mjOBJ_GEOM, int(c.geom1)),
                    mujoco.mj_id2name(world.model, mujoco.mjtObj.mjOBJ_GEOM, int(c.geom2))}
            assert not (pair & names and any(p.startswith("clutter") for p in pair)), (seed, pair)
        assert len(setup.scene.geometry) == 1 + TASKS.get("pick-clutter").factory().config({}).clutter.distractors


@pytest.mark.parametrize("task", ["push-pick-board", "pick-box", "pick-clutter", "push-force", "flip-box", "flip-wall"])
def test_every_task_has_both_expert_designs(task: str) -> None:
    from kintsugi.methods.expert.designs import EXPERTS

    assert task in EXPERTS


def _board_pushed(robot, cfg, setup, overhang_m: float):  # noqa: ANN001, ANN202
    """Push the board's back edge with the closed fingers (plain servo targets) until the handle overhangs."""
    from kintsugi.worlds.contact.push_pick_board import overhang

    geo = setup.scene.geometry["board"]
    b = robot.observe().objects["board"]
    back = b.pos[0] - geo.parts[0].half[0]
    robot.act(np.array([back - 0.04, b.pos[1], 0.05, 0, 0]), 0.8)
    robot.act(np.array([back - 0.03, b.pos[1], 0.004, 0, 0]), 0.6)
    for _ in range(300):
        o = robot.observe()
        b = o.objects["board"]
        if overhang(b.pos, b.quat, geo, cfg.table.edge_x_m) >= overhang_m:
            break
        robot.act(np.array([o.ee[0] + 0.005, b.pos[1], 0.004, 0, 0]), 0.05)
    o = robot.act(np.array([o.ee[0] - 0.03, o.ee[1], 0.07, 0, 0]), 0.6)
    return o.objects["board"]


def _pinch_handle(robot, cfg, board, z: float) -> None:  # noqa: ANN001
    """Come down round the handle 3.5 cm past the table edge to fingertip height z, and close."""
    from kintsugi.worlds.contact.world import yaw_of

    yaw = float(yaw_of(board.quat))
    s = (cfg.table.edge_x_m + 0.035 - board.pos[0]) / np.cos(yaw)
    g = board.pos + s * np.array([np.cos(yaw), np.sin(yaw), 0.0])
    robot.act(np.array([g[0], g[1], 0.07, yaw, 0.09]), 1.0)
    robot.act(np.array([g[0], g[1], z, yaw, 0.09]), 0.8)
    robot.act(np.array([g[0], g[1], z, yaw, 0.0]), 0.6)


@pytest.mark.slow
def test_push_pick_board_scores_a_board_lifted_by_its_overhanging_handle() -> None:
    cfg, world, scorer, setup = _task("push-pick-board")
    robot = ContactRobot(world, watchers=[scorer.watch])
    ok, details = scorer.finish(world)
    assert not ok and details.max_overhang_m < 0 and not details.pinched
    board = _board_pushed(robot, cfg, setup, 0.095)
    _pinch_handle(robot, cfg, board, -0.012)
    o = robot.observe()
    assert o.ee[2] < -0.005 and o.touch.min() > 5  # below the board's bottom: only possible past the edge
    for z in np.linspace(-0.012, 0.28, 30):
        o = robot.act(np.array([*o.ee[:2], z, o.ee[3], 0.0]), 0.05)
    robot.act(np.array([*o.ee[:3], o.ee[3], 0.0]), 2.0)
    ok, details = scorer.finish(world)
    assert ok, details
    assert details.max_overhang_m >= cfg.scoring.min_overhang_m and details.lowest_z_m >= cfg.scoring.lift_m
    robot.act(np.array([*o.ee[:3], o.ee[3], 0.09]), 1.5)  # let go: it falls, not held
    ok, details = scorer.finish(world)
    assert not ok and not details.pinched


def test_push_pick_board_handle_on_the_table_cannot_be_reached_from_below() -> None:
    cfg, world, scorer, setup = _task("push-pick-board")
    robot = ContactRobot(world, watchers=[scorer.watch])
    board = robot.observe().objects["board"]
    # the same grasp, without the push: the fingers come down on the table behind the edge
    geo = setup.scene.geometry["board"]
    tip_x = board.pos[0] + geo.parts[1].pos[0] + geo.parts[1].half[0]
    robot.act(np.array([tip_x - 0.03, board.pos[1], 0.07, 0, 0.09]), 1.0)
    o = robot.act(np.array([tip_x - 0.03, board.pos[1], -0.012, 0, 0.09]), 1.0)
    assert o.ee[2] > -0.002  # the table stops them: no pinch under the board here
    ok, _ = scorer.finish(world)
    assert not ok


def test_push_pick_board_draws_its_sizes_and_start_from_the_config() -> None:
    from kintsugi.worlds.contact.push_pick_board import overhang

    for seed in range(4):
        cfg, world, _, setup = _task("push-pick-board", "random", seed)
        b = cfg.board
        p = setup.params
        assert b.plate_m[0][0] <= p["board.plate_x_m"] <= b.plate_m[0][1]
        assert b.mass_kg[0] <= setup.truth["board"].mass_kg <= b.mass_kg[1]
        pos, quat = world.object_pose("board")
        gap = -float(overhang(pos, quat, setup.scene.geometry["board"], cfg.table.edge_x_m))
        assert b.gap_m[0] - 0.01 <= gap <= b.gap_m[1] + 0.01  # yaw moves one tip corner a little
