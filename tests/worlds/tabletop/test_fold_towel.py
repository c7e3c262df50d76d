"""fold-towel: the cloth's mesh, its config, perceived corners, friction pinching on real flex
physics (a pinch lifts the corner, round pads lose it, a drop lets it fall), and the judge."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import numpy as np
import pytest

from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.worlds.tabletop.cloth import CORNERS, TOWEL, corner_indices, grid_triangles
from kintsugi.worlds.tabletop.fold_towel import ARM_CORNERS, script
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.task import expand
from kintsugi.worlds.tabletop.world import TabletopWorld
from tests.sim_checks import assert_no_warnings

load_builtins()
GRASP_STEPS = 3
"""The script's first three entries: above the corners, down to the table, close."""


def _task():  # noqa: ANN202
    return TASKS.get("fold-towel").factory()


def _truth_corners(world: TabletopWorld) -> dict[str, np.ndarray]:
    v = world.flex_vertices(0)
    return {k: v[i] for k, i in corner_indices(world.cfg.towel.count).items()}


def _grasped(overrides: dict | None = None, condition: str = "none", seed: int = 0
             ) -> tuple[TabletopWorld, TabletopRobot, object]:
    task = _task()
    world, scorer, hook, _ = task.build(task.config(overrides or {}), condition, seed)
    robot = TabletopRobot(world, hook=hook)
    steps = script(robot.observation(images=False))
    for action in steps[:GRASP_STEPS]:
        robot.execute(action)
    return world, robot, scorer


def _lift(robot: TabletopRobot, dz: float = 0.08) -> None:
    robot.execute({"action": "drive", **{a: {"action": "move_by_offset", "arm": a, "dxyz": (0.0, 0.0, dz)}
                                         for a in ARM_CORNERS}})


def test_mesh_puts_every_corner_on_its_quads_diagonal() -> None:
    n = 9
    tris = grid_triangles(n)
    assert len(tris) == 2 * (n - 1) ** 2
    for corner in corner_indices(n).values():
        # the corner quad's two triangles both contain the corner: the diagonal runs through it
        assert sum(corner in t for t in tris) == 2, corner


def test_config_errors_name_the_key() -> None:
    task = _task()
    with pytest.raises(ConfigError, match="towel.count"):
        task.config({"towel.count": 2})
    with pytest.raises(ConfigError, match="towel.no_such_key"):
        task.config({"towel.no_such_key": 1})
    with pytest.raises(ConfigError, match="fold.corner_tol_m"):
        task.config({"fold.corner_tol_m": -0.01})
    with pytest.raises(ConfigError, match="towel"):  # the rigid tasks have no towel section
        TASKS.get("pour-single").factory().config({"towel.count": 9})


def test_rigid_tasks_keep_their_physics() -> None:
    rigid = TASKS.get("pour-single").factory().config({})
    towel = _task().config({})
    assert rigid.robot.pad_shape == "capsule" and rigid.robot.gripper_open_force_n is None
    assert towel.robot.pad_shape == "box" and towel.towel.integrator == "discrete"


def test_perceived_corners_are_near_the_true_ones_and_pose_is_randomized() -> None:
    task = _task()
    drawn = []
    for seed in (0, 1):
        world, _, _, params = task.build(task.config({}), "pose", seed)
        drawn.append(params.towel)
        feats = TabletopRobot(world).features()
        assert set(feats) == {TOWEL} and feats[TOWEL].visible and feats[TOWEL].note != "ground truth"
        truth = _truth_corners(world)
        for k in CORNERS:
            err = np.linalg.norm(np.array(feats[TOWEL].extremes[f"corner_{k}"])[:2] - truth[k][:2])
            assert err < 0.008, (seed, k, err)
        world.close()
    assert drawn[0] != drawn[1]
    none = task.build(task.config({}), "none", 3)[3].towel
    assert (none.x, none.y, none.yaw_deg) == (0.38, 0.0, 0.0)


def test_unfolded_towel_is_not_a_fold() -> None:
    task = _task()
    world, scorer, _, _ = task.build(task.config({}), "none", 0)
    for _ in range(5):
        world.tick()
    ok, d = scorer.finish(world)
    assert not ok and not d.lifted and d.released
    assert min(d.corner_dist_m.values()) > 0.9 * world.cfg.towel.side_m
    world.close()


@pytest.fixture(scope="module")
def lifted() -> dict[str, object]:
    world, robot, scorer = _grasped()
    out: dict[str, object] = {"touch": {a: world.pad_contacts(a)[0].get(TOWEL) for a in ARM_CORNERS}}
    _lift(robot)
    c = _truth_corners(world)
    out["lift_z"] = {a: float(c[ARM_CORNERS[a][0]][2]) for a in ARM_CORNERS}
    out["held"] = world.ground_truth().held
    world.force_open("left", world.cfg.disturbance.drop_release_s)  # what the drop disturbance does
    for _ in range(90):  # (still inside the forced opening)
        world.tick()
    c = _truth_corners(world)
    out["after_drop_z"] = {a: float(c[ARM_CORNERS[a][0]][2]) for a in ARM_CORNERS}
    out["after_drop_touch"] = {a: world.pad_contacts(a) for a in ARM_CORNERS}
    out["after_drop_opening"] = world.gripper_opening("left")
    out["world"] = world
    world.close()
    return out


@pytest.mark.slow
def test_pinch_lifts_both_corners_by_friction(lifted: dict) -> None:
    assert lifted["touch"] == {"left": 2, "right": 2}
    assert all(z > 0.06 for z in lifted["lift_z"].values()), lifted["lift_z"]
    assert all(TOWEL in objs for objs in lifted["held"].values())
    assert_no_warnings(lifted["world"])


@pytest.mark.slow
def test_an_opened_gripper_lets_go_of_its_corner(lifted: dict) -> None:
    """The drop disturbance's forced opening ends the pinch: fully open, at most one pad brushing the
    cloth with next to no force. (The corner need not fall: here it hangs draped over the open pad,
    which is how a release fails - see the report on the scripted fold's release.)"""
    left, right = lifted["after_drop_touch"]["left"], lifted["after_drop_touch"]["right"]
    assert lifted["after_drop_opening"] > 0.09
    assert left[0].get(TOWEL, 0) <= 1 and left[1] < 0.5, left
    assert right[0].get(TOWEL) == 2 and lifted["after_drop_z"]["right"] > 0.06  # the other arm still holds


@pytest.mark.slow
def test_too_weak_a_pinch_loses_the_corner() -> None:
    """Friction only: with a feeble squeeze the pinched corners slide out of the pads on the lift."""
    world, robot, _ = _grasped({"robot.grip_force_n": 0.02})
    _lift(robot)
    c = _truth_corners(world)
    assert all(c[b][2] < 0.02 for b, _ in ARM_CORNERS.values()), c
    world.close()


@pytest.mark.slow
def test_drop_condition_releases_a_held_corner() -> None:
    """Under `drop` with p = 1 the first action after the pinch opens a gripper at a random instant."""
    world, robot, _ = _grasped({"disturbance.drop_p": 1.0}, condition="drop")
    hook = robot._hook
    _lift(robot)
    for _ in range(110):
        world.tick()
    assert any("dropped towel" in what for _, what in hook.parts[0].events), hook.parts[0].events
    c = _truth_corners(world)
    assert min(c[b][2] for b, _ in ARM_CORNERS.values()) < 0.02
    world.close()


@pytest.mark.slow
def test_scripted_fold_with_perceived_corners_folds_and_lets_go() -> None:
    """The whole scripted fold on a randomized pose from perceived corners: the pinch (6 N) lets the
    cloth go when the pads open (at 20 N the pads press through the coarse cloth and drag it off on
    the retreat), and the lifted half falls flat with its corners on the top ones."""
    task = _task()
    world, scorer, hook, _ = task.build(task.config({}), "pose", 3)
    robot = TabletopRobot(world, hook=hook)
    assert robot.observation(images=False).features_source == "perceived"
    for entry in script(robot.observation(images=False)):
        for action in expand(entry, robot):
            assert not robot.execute(action).ik_failed, action
    ok, d = scorer.finish(world)
    assert ok and d.released and d.at_rest, d
    assert max(d.corner_dist_xy_m.values()) < 0.005, d
    assert_no_warnings(world)
    world.close()
