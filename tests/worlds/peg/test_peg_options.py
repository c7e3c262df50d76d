"""Options beyond the paper's limits, on the world side: re-approach as a recovery skill,
`recovery.skills`, the hole's x offset and the side camera (x-z plane)."""

from __future__ import annotations

import math

import kintsugi  # noqa: F401 - MUJOCO_GL before mujoco
import numpy as np
import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import METHODS
from kintsugi.methods.recovery.settings import RecoverySettings

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.perception.segment import measure
from kintsugi.worlds.peg.conditions import sample_params
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import full_goals, load_goals
from kintsugi.worlds.peg.skills import SEQUENCE, execute_skill
from kintsugi.worlds.peg.world import HOME_POSE, PegWorld, TrialParams

CFG = PegTaskConfig()
SIDE = apply_overrides(CFG, ["camera.side_view=true"])


# --- re-approach ---------------------------------------------------------

def test_reapproach_backs_a_jammed_peg_out_and_a_corrected_sequence_inserts_it() -> None:
    """The taught goals jam the square peg 17 mm deep at 8.7 deg against a hole 17.7 mm off.
    Approach (goal above the board) first rises straight up, so the peg leaves the hole without
    being dragged sideways; the rest of the sequence shifted onto the hole then inserts it."""
    hole_y = 17.72
    world = PegWorld(CFG, TrialParams(shape="square", hole_y_mm=hole_y, grasp_angle_deg=0.11))
    targets = full_goals(load_goals(), HOME_POSE)
    for skill in SEQUENCE:
        execute_skill(world, skill, targets[skill])
    jammed = world.ground_truth()
    assert jammed.inside_hole and not jammed.success
    start = world.base_pose()

    shift = np.array([hole_y / 1000, 0.0, math.radians(-2.0)])  # a plan's corrected y and roll
    path: list[np.ndarray] = []
    approach = targets["approach"] + shift
    result = execute_skill(world, "approach", approach, on_tick=lambda w: path.append(w.base_pose()))
    assert result.reached and not result.compression_limit and not result.timed_out
    path_arr = np.array(path)
    rising = path_arr[:, 1] < approach[1] - 1e-9
    assert rising[0] and np.allclose(path_arr[rising, 0], start[0]) and np.allclose(path_arr[rising, 2], start[2])
    assert world.ground_truth().tip_depth_mm < 0  # out of the hole, above the board

    for skill in ("contact", "fit", "align", "insert"):
        goal = targets[skill].copy()
        goal[0] += shift[0]
        goal[2] = approach[2]
        execute_skill(world, skill, goal)
    truth = world.ground_truth()
    assert truth.success, truth


def test_approach_from_home_is_the_taught_straight_line() -> None:
    """From home the approach goal is lower, so the path is the published straight line."""
    world = PegWorld(CFG, TrialParams(shape="round"))
    goal = full_goals(load_goals(), HOME_POSE)["approach"]
    path: list[np.ndarray] = []
    execute_skill(world, "approach", goal, on_tick=lambda w: path.append(w.base_pose()))
    p = np.array(path)[:, :2]
    direction = (goal[:2] - HOME_POSE[:2]) / np.linalg.norm(goal[:2] - HOME_POSE[:2])
    off_line = (p - HOME_POSE[:2]) @ np.array([-direction[1], direction[0]])
    assert np.abs(off_line).max() < 1e-9


load_builtins()


# --- the recovery method's skills setting -----------------------------------------------------

def test_recovery_skills_default_is_the_papers() -> None:
    assert RecoverySettings().skills == ("fit", "align", "insert")


def test_recovery_skills_accept_reapproach_in_cf_order() -> None:
    cfg = METHODS.get("recovery").configure(['skills=["insert","approach","fit","align","contact"]'])
    assert cfg.skills == ("approach", "contact", "fit", "align", "insert")


@pytest.mark.parametrize(("value", "needle"), [
    ('["fit","wiggle"]', "'wiggle'"),
    ('["fit","fit"]', "fit more than once"),
    ("[]", "at least one"),
    ("fit", "method.skills"),
])
def test_recovery_skills_rejects_bad_lists_by_name(value: str, needle: str) -> None:
    with pytest.raises(ConfigError) as exc:
        METHODS.get("recovery").configure([f"skills={value}"])
    msg = str(exc.value)
    assert "method.skills" in msg and needle in msg and "'recovery'" in msg, msg
    if "wiggle" in needle:
        assert "approach, contact, fit, align, insert" in msg


# --- hole x offset -------------------------------------------------------

def test_hole_x_offset_is_drawn_last_and_only_under_pose() -> None:
    cfg = apply_overrides(CFG, ["hole.x_offset_mm=[-3,3]"])
    for seed in range(5):
        plain = sample_params(CFG, "round", "all", seed)
        with_x = sample_params(cfg, "round", "all", seed)
        assert plain.hole_x_mm == 0.0 and -3 <= with_x.hole_x_mm <= 3 and with_x.hole_x_mm != 0.0
        assert with_x.model_dump(exclude={"hole_x_mm"}) == plain.model_dump(exclude={"hole_x_mm"})
        assert sample_params(cfg, "round", "friction", seed).hole_x_mm == 0.0
        assert sample_params(cfg, "round", "pose", seed).hole_x_mm == with_x.hole_x_mm


def test_hole_x_offset_moves_the_physical_hole() -> None:
    """Straight down over a hole 4 mm off along x: the peg lands on the far wall's rim
    (1 mm radial clearance), while the same push over the moved hole goes in."""
    tip_from_base = CFG.wrist.hinge_to_grasp_mm / 1000 + CFG.peg.length_mm / 1000
    for hole_x, inserted in ((0.0, True), (4.0, False)):
        world = PegWorld(CFG, TrialParams(shape="square", hole_x_mm=hole_x))
        world.set_base(np.array([0.0, 0.16, 0.0]))
        world.step(200)
        execute_skill(world, "insert", np.array([0.0, tip_from_base - 0.025, 0.0]))
        truth = world.ground_truth()
        assert truth.success is inserted, truth
        assert truth.tip_offset_x_mm == pytest.approx(-hole_x, abs=0.6)


# --- side camera ---------------------------------------------------------

@pytest.mark.parametrize("shape", ["round", "rectangle", "polygon5"])
def test_side_view_rim_spans_the_opening_along_x(shape: str) -> None:
    world = PegWorld(SIDE, TrialParams(shape=shape, hole_x_mm=3.0, hole_y_mm=-12.0))
    cal = world.side_calibration()
    seen = measure(world.render_side(), cal, SIDE.perception)
    px = 1 / cal.px_per_mm
    x0, x1 = (v * 1000 + 3.0 for v in world.hole.x_range)
    assert seen.hole is not None and seen.peg is not None
    assert seen.hole.left_mm == pytest.approx(x0, abs=px)
    assert seen.hole.right_mm == pytest.approx(x1, abs=px)
    assert seen.hole.top_mm == pytest.approx(0.0, abs=px)
    world.close()


def test_side_view_sees_the_pitch_the_main_view_cannot() -> None:
    """Tilt the peg out of the main camera's plane (about y): the side image measures the tilt,
    the main image sees the peg upright."""
    world = PegWorld(SIDE, TrialParams(shape="round"))
    world.set_base(np.array([-0.05, 0.16, 0.0]))
    world.step(100)
    pitch = world.model.jnt_qposadr[world.model.joint("wrist_pitch").id]
    world.data.qpos[pitch] = math.radians(6.0)
    world.data.qvel[:] = 0.0
    import mujoco

    mujoco.mj_kinematics(world.model, world.data)
    side = measure(world.render_side(), world.side_calibration(), SIDE.perception)
    main = measure(world.render(), world.calibration(), SIDE.perception)
    assert side.peg is not None and main.peg is not None
    assert abs(side.peg.tilt_deg) == pytest.approx(6.0, abs=1.0)
    assert abs(main.peg.tilt_deg) < 1.0
    world.close()


def test_side_view_leaves_the_main_image_and_physics_alone() -> None:
    plain = PegWorld(CFG, TrialParams(shape="square", hole_y_mm=5.0))
    side = PegWorld(SIDE, TrialParams(shape="square", hole_y_mm=5.0))
    assert np.array_equal(plain.render(), side.render())
    goal = full_goals(load_goals(), HOME_POSE)
    for skill in ("approach", "contact", "fit"):
        a = execute_skill(plain, skill, goal[skill])
        b = execute_skill(side, skill, goal[skill])
        assert np.array_equal(a.terminal, b.terminal) and a.compression == b.compression
    assert np.array_equal(plain.data.qpos, side.data.qpos)
    plain.close()
    side.close()


def test_no_side_camera_unless_configured() -> None:
    world = PegWorld(CFG, TrialParams(shape="round"))
    assert not world.has_side_view
    with pytest.raises(ConfigError, match="camera.side_view"):
        world.render_side()
    with pytest.raises(ConfigError, match="camera.side_view"):
        world.side_calibration()
