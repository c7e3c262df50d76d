"""Tabletop actions, IK and observations: validated calls, real reachability, honest observations."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import numpy as np
import pytest

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.worlds.tabletop.actions import ActionError
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.ik import ArmIK
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

START = {"bottle": StartPose(x=0.40, y=-0.25), "cup": StartPose(x=0.46, y=0.0)}


@pytest.fixture(scope="module")
def scene() -> tuple[TabletopWorld, TabletopRobot]:
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    yield world, TabletopRobot(world)
    world.close()


def _rot_err_deg(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1.0, 1.0))))


@pytest.mark.parametrize("arm", ["left", "right"])
def test_ik_reaches_reachable_targets_within_1mm_and_1deg(arm: str) -> None:
    cfg = TabletopConfig()
    ik = ArmIK(cfg.robot, cfg.motion, arm)
    rng = np.random.default_rng(1)
    solved = 0
    for _ in range(40):
        # Configurations around the working posture: every target is reachable by construction.
        q = np.clip(ik.home + rng.uniform(-0.7, 0.7, 6), ik.lower, ik.upper)
        pos, rot = ik.fk(q)
        result = ik.solve(pos, rot, ik.home)
        if result.clipped:
            continue
        assert result.ok, result.message()
        got_pos, got_rot = ik.fk(result.q)  # check independently of the solver's own residual
        assert np.linalg.norm(got_pos - pos) <= 1e-3
        assert _rot_err_deg(got_rot, rot) <= 1.0
        assert np.all(result.q >= ik.lower - 1e-6) and np.all(result.q <= ik.upper + 1e-6)
        solved += 1
    assert solved >= 20


def test_unreachable_target_is_an_ik_failure_and_nothing_moves(scene) -> None:
    world, robot = scene
    q0, steps0 = world.joint_targets("right").copy(), world.steps
    # Inside the workspace box, but 0.95 m from the right shoulder: beyond the arm's reach.
    result = robot.execute({"action": "move_to_target", "arm": "right", "xyz": (0.72, 0.55, 0.05),
                            "rpy_deg": (180.0, 0.0, 0.0)})
    assert result.ik_failed and not result.reached
    assert "cannot reach" in result.message
    assert world.steps == steps0 and np.array_equal(world.joint_targets("right"), q0)


def test_plan_only_moves_nothing_and_says_whether_a_target_was_clipped(scene) -> None:
    world, robot = scene
    q0, steps0 = world.joint_targets("right").copy(), world.steps
    far = robot.execute({"action": "move_to_target", "arm": "right", "xyz": (0.8, -0.3, 0.3),
                          "rpy_deg": (0.0, 90.0, 0.0)}, plan_only=True)
    grasp = robot.execute({"action": "grasp", "arm": "right", "obj": "bottle"}, plan_only=True)
    assert far.planned and far.clipped and grasp.planned and not grasp.clipped and not grasp.reached
    assert world.steps == steps0 and np.array_equal(world.joint_targets("right"), q0)


def test_targets_are_clipped_to_the_workspace(scene) -> None:
    cfg = TabletopConfig()
    ik = ArmIK(cfg.robot, cfg.motion, "right")
    pos, clipped = ik.clip(np.array([0.3, -0.2, -0.05]))
    assert clipped and pos[2] == pytest.approx(cfg.motion.workspace_z_m[0])


@pytest.mark.parametrize(("action", "needles"), [
    ({"action": "fly", "arm": "right"}, ["unknown action 'fly'", "grasp"]),
    ({"action": "grasp", "arm": "right"}, ["grasp", "obj", "Field required"]),
    ({"action": "grasp", "arm": "middle", "obj": "bottle"}, ["arm", "'left' or 'right'"]),
    ({"action": "grasp", "arm": "right", "obj": "botle"}, ["unknown object 'botle'", "bottle, cup"]),
    ({"action": "place", "arm": "right", "x": "far", "y": 0.1}, ["place", "x", "valid number"]),
    ({"action": "rotate_eef", "arm": "right", "angle_deg": 90, "speed": 2}, ["speed", "Extra inputs"]),
    ({"action": "drive", "left": {"action": "back", "arm": "right"}}, ["drive.left", "right arm"]),
    ({"action": "drive", "right": {"action": "grasp", "arm": "right", "obj": "plate"}}, ["unknown object 'plate'"]),
])
def test_bad_actions_raise_one_clear_error_and_nothing_moves(scene, action: dict, needles: list[str]) -> None:
    world, robot = scene
    qpos, steps0 = world.data.qpos.copy(), world.steps
    with pytest.raises(ActionError) as err:
        robot.execute(action)
    for needle in needles:
        assert needle in str(err.value), str(err.value)
    assert world.steps == steps0 and np.array_equal(world.data.qpos, qpos)


def test_drive_moves_both_arms_at_once() -> None:
    world = TabletopWorld(TabletopConfig(), ["bottle"], {"bottle": StartPose(x=0.4, y=-0.25)})
    robot = TabletopRobot(world)
    up = (0.0, 0.0, 0.08)
    start = {arm: robot.arm_state(arm).tcp_pos for arm in ("left", "right")}
    result = robot.execute({"action": "drive", "left": {"action": "move_by_offset", "arm": "left", "dxyz": up},
                            "right": {"action": "move_by_offset", "arm": "right", "dxyz": up}})
    assert result.reached and result.arms == ("left", "right")
    for arm in ("left", "right"):
        assert robot.arm_state(arm).tcp_pos[2] - start[arm][2] == pytest.approx(0.08, abs=0.003)
    single = robot.execute({"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, -0.08)})
    assert result.steps < 1.3 * single.steps  # simultaneous, not one after the other
    world.close()


def test_observation_is_perceived_and_ground_truth_is_not_reachable(scene) -> None:
    world, robot = scene
    obs = robot.observation()
    assert obs.features_source == "perceived"
    assert set(obs.images_png) == {"top", "front"}
    assert all(png.startswith(b"\x89PNG") for png in obs.images_png.values())
    truth = world.ground_truth().objects
    for name in ("bottle", "cup"):
        f = obs.objects[name]
        assert f.visible and f.note != "ground truth" and f.upright
        assert np.linalg.norm(np.array(f.centroid) - np.array(truth[name].pos)) < 0.008
    arm = obs.arms["right"]
    assert len(arm.joints_deg) == 6 and 0.0 <= arm.gripper_opening_m <= 0.1 + 1e-6
    exposed = [k for k, v in vars(robot).items() if not k.startswith("_") and isinstance(v, TabletopWorld)]
    assert not exposed and not hasattr(robot, "world")


def test_truth_features_are_an_explicit_option() -> None:
    cfg = apply_overrides(TabletopConfig(), {"perception.objects": "truth"})
    world = TabletopWorld(cfg, ["bottle"], {"bottle": StartPose(x=0.4, y=-0.25)})
    obs = TabletopRobot(world).observation(images=False)
    assert obs.features_source == "truth" and obs.objects["bottle"].note == "ground truth"
    world.close()


def test_bad_config_names_the_key() -> None:
    with pytest.raises(ConfigError, match="robot.grip_forse_n"):
        apply_overrides(TabletopConfig(), {"robot.grip_forse_n": 5})
    with pytest.raises(ConfigError, match="robot.grip_force_n"):
        apply_overrides(TabletopConfig(), {"robot.grip_force_n": -1})
    with pytest.raises(ConfigError, match="perception.objects"):
        apply_overrides(TabletopConfig(), {"perception.objects": "oracle"})


def test_methods_declare_their_tasks() -> None:
    record = run_trial(TrialSpec(task="pour-single", method="recovery", variant="default", condition="none", seed=0))
    assert record.error and "does not run task 'pour-single'" in record.error and "scripted" in record.error
    record = run_trial(TrialSpec(task="peg-insertion", method="scripted", variant="round", condition="none", seed=0))
    assert record.error and "does not run task 'peg-insertion'" in record.error and "baseline" in record.error
