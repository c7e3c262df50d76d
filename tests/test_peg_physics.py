"""Physics soundness of the soft-wrist peg world: springs, contacts, hole geometry, conditions.

Every check measures the compiled MuJoCo model (not the config it came from), so a
wrong MJCF, a wrong unit or a soft contact fails here rather than in a campaign.
"""

from __future__ import annotations

import math

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest

from kintsugi.tasks import load_all
from kintsugi.tasks.peg.conditions import sample_params
from kintsugi.tasks.peg.config import PegTaskConfig
from kintsugi.tasks.peg.scene import WALL_THICK
from kintsugi.tasks.peg.shapes import MM, hole_for, peg_shape
from kintsugi.tasks.peg.skills import execute_skill
from kintsugi.tasks.peg.world import PegWorld, TrialParams
from kintsugi.trial import TrialSpec, run_trial

load_all()  # run_trial looks the task up in the registry

SHAPES = ("round", "square", "rectangle", "polygon6")
CFG = PegTaskConfig()
GRASP_TO_TIP = CFG.wrist.hinge_to_grasp_mm * MM + CFG.peg.length_mm * MM  # base origin -> peg tip, upright
AWAY_Y = -0.10  # on the board's top plate, far from the hole (plate spans |y| in [0.04, 0.16])


def _world(shape: str = "round", **params: float) -> PegWorld:
    return PegWorld(CFG, TrialParams(shape=shape, **params))


def _body(world: PegWorld, name: str) -> int:
    return mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_BODY, name)


def _tip_z(world: PegWorld) -> float:
    return float(world.data.site_xpos[mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_SITE, "peg_tip")][2])


def _hold(world: PegWorld, pose: tuple[float, float, float], seconds: float) -> None:
    world.set_base(np.array(pose))
    world.step(round(seconds / world.model.opt.timestep))


def _no_warnings(world: PegWorld) -> None:
    counts = {mujoco.mjtWarning(i).name: world.data.warning[i].number for i in range(mujoco.mjtWarning.mjNWARNING)}
    assert not any(counts.values()), counts
    assert np.all(np.isfinite(world.data.qpos)) and np.all(np.isfinite(world.data.qvel))


# --- springs -------------------------------------------------------------

@pytest.mark.parametrize("force", [10.0, -10.0, 4.0])
def test_z_spring_static_deflection_is_force_over_stiffness(force: float) -> None:
    """A known vertical force on the peg deflects the z slide by F/k (tared, gravity preloaded)."""
    world = _world()
    _hold(world, (-0.05, 0.25, 0.0), 0.5)  # free air, well above the board
    assert abs(world.wrist_compression()) < 1e-5, "hanging wrist must rest at zero compression"
    world.data.xfrc_applied[_body(world, "peg")] = (0, 0, force, 0, 0, 0)
    world.step(4000)  # lightly damped (zeta ~ 0.03): 4 s settles well below 1 %
    expected = force / CFG.wrist.z_stiffness
    assert world.wrist_compression() == pytest.approx(expected, rel=0.05)
    # The robot-side force sensor reports the same force.
    assert world.wrist_compression() * CFG.wrist.z_stiffness == pytest.approx(force, rel=0.05)
    _no_warnings(world)


@pytest.mark.parametrize("torque", [0.05, -0.03])
def test_roll_spring_static_deflection_is_torque_over_stiffness(torque: float) -> None:
    """A known torque about x deflects the roll hinge by tau/k (Nm/rad), gravity off so the
    hanging gripper+peg pendulum does not add its own restoring torque."""
    world = _world()
    _hold(world, (-0.05, 0.25, 0.0), 0.2)
    world.model.opt.gravity[:] = 0.0
    world.data.xfrc_applied[_body(world, "peg")] = (0, 0, 0, torque, 0, 0)
    world.step(4000)
    roll = world.wrist_deflection()[1]
    assert roll == pytest.approx(torque / CFG.wrist.roll_stiffness, rel=0.05)
    assert abs(world.wrist_deflection()[2]) < 1e-4 and abs(world.wrist_deflection()[3]) < 1e-4
    _no_warnings(world)


def test_roll_spring_with_gravity_adds_pendulum_stiffness() -> None:
    """With gravity on, the same torque deflects less: k + m g l of everything below the hinge."""
    world = _world()
    _hold(world, (-0.05, 0.25, 0.0), 0.2)
    torque = 0.03
    world.data.xfrc_applied[_body(world, "peg")] = (0, 0, 0, torque, 0, 0)
    world.step(4000)
    roll = world.wrist_deflection()[1]
    m, d = world.model, world.data
    below = _body(world, "gripper")
    hinge = d.xpos[_body(world, "wrist_roll")]
    mass = m.body_subtreemass[below]
    lever = np.linalg.norm(d.subtree_com[below] - hinge)
    k_eff = CFG.wrist.roll_stiffness + mass * 9.81 * lever * math.sin(roll) / roll
    assert roll == pytest.approx(torque / k_eff, rel=0.05)
    assert abs(roll) < torque / CFG.wrist.roll_stiffness


# --- contacts ------------------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_peg_pressed_with_20N_on_the_board_does_not_sink(shape: str) -> None:
    world = _world(shape)
    _hold(world, (AWAY_Y, 0.16, 0.0), 0.3)
    # Drive the base so an unobstructed tip would end 20 mm below the surface -> ~20 N on the spring.
    target = GRASP_TO_TIP - 0.0198  # just inside the 20 mm compression limit
    result = execute_skill(world, "contact", np.array([AWAY_Y, target, 0.0]))
    assert not result.compression_limit
    world.step(1000)
    force = world.wrist_compression() * CFG.wrist.z_stiffness
    assert force == pytest.approx(19.8, abs=0.5)
    assert _tip_z(world) > -1e-3, f"tip sank {-_tip_z(world) / MM:.2f} mm into the board under {force:.1f} N"
    # The contract is 1 mm; the model measures ~0.01 mm, so guard that too (0.1 mm fails at
    # sim.contact_timeconst_s = 0.01, 1 mm only at ~0.05).
    assert _tip_z(world) > -0.1e-3
    assert _tip_z(world) < 1e-3, "the peg should be resting on the surface"
    _no_warnings(world)


@pytest.mark.parametrize("shape", SHAPES)
def test_peg_cannot_pass_through_the_board_and_the_limit_halts_at_once(shape: str) -> None:
    """Drive the base 30 cm below the surface away from the hole: the compression limit
    stops the skill immediately, the base stops where the spring reached the limit, and the
    peg stays on top of the board."""
    world = _world(shape)
    _hold(world, (AWAY_Y, 0.16, 0.0), 0.3)
    result = execute_skill(world, "contact", np.array([AWAY_Y, -0.10, 0.0]))
    limit = CFG.control.compression_limit_mm * MM
    assert result.compression_limit and not result.reached and not result.timed_out
    # "At once": compression at most one control tick (speed x 1/rate) past the limit.
    tick = CFG.control.speed_mm_s * MM / CFG.control.rate_hz
    assert limit < result.compression <= limit + tick + 0.2 * MM
    assert result.max_compression == pytest.approx(result.compression, abs=1e-6)
    # The base stopped about `limit` below first contact (tip at z = 0), not at its goal.
    assert result.terminal[1] == pytest.approx(GRASP_TO_TIP - limit, abs=0.5 * MM)
    # Sim time: exactly the descent (40 mm at 40 mm/s + the limit) and no settle wait.
    descent = (0.16 - result.terminal[1]) / (CFG.control.speed_mm_s * MM)
    assert result.sim_time == pytest.approx(descent, abs=2 / CFG.control.rate_hz)
    assert _tip_z(world) > -1e-3
    _no_warnings(world)


# --- hole geometry -------------------------------------------------------

def _ray_distance(world: PegWorld, origin: tuple[float, float, float], direction: tuple[float, float, float]) -> float:
    geomid = np.zeros(1, dtype=np.int32)
    dist = mujoco.mj_ray(world.model, world.data, np.array(origin, float), np.array(direction, float),
                         None, 1, _body(world, "peg"), geomid)
    assert dist > 0, f"ray from {origin} along {direction} hit nothing"
    return dist


@pytest.mark.parametrize("shape", SHAPES)
def test_hole_opening_is_peg_plus_half_clearance(shape: str) -> None:
    peg = peg_shape(shape, CFG)
    hole = hole_for(peg, CFG)
    c = CFG.peg.clearance_mm / 2 * MM
    assert hole.y_range[1] == pytest.approx(peg.half_y + c, abs=1e-9)
    # Measured in the compiled world: rays from the hole axis, 20 mm down, hit the walls
    # at the half opening along +-y (and +-x: the peg's depth half extent + clearance/2).
    world = _world(shape)
    mujoco.mj_forward(world.model, world.data)
    origin = (0.0, 0.0, -0.02)
    for direction, edge in (((0, 1, 0), hole.y_range[1]), ((0, -1, 0), -hole.y_range[0])):
        assert _ray_distance(world, origin, direction) == pytest.approx(edge, abs=1e-6)
    half_x = peg.half_x if peg.kind != "prism" else peg.circumradius * math.cos(math.pi / peg.sides)
    # Polygon holes: x is a vertex direction unless a side faces it; measure along the side normals.
    for angle, inset in hole.sides:
        assert _ray_distance(world, origin, (math.sin(angle), math.cos(angle), 0)) == pytest.approx(inset, abs=1e-6)
    if peg.kind != "prism":
        assert _ray_distance(world, origin, (1, 0, 0)) == pytest.approx(half_x + c, abs=1e-6)
    # The wall boxes' inner faces are exactly at the insets (no gap in the ring at the rim).
    for k, (angle, inset) in enumerate(hole.sides):
        g = mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, f"wall{k}")
        pos = world.data.geom_xpos[g]
        along_normal = pos[0] * math.sin(angle) + pos[1] * math.cos(angle)
        assert along_normal - WALL_THICK / 2 == pytest.approx(inset, abs=1e-6)  # MJCF keeps 6 digits


@pytest.mark.parametrize("shape", SHAPES)
def test_upright_peg_over_the_hole_centre_goes_in(shape: str) -> None:
    world = _world(shape)
    _hold(world, (0.0, 0.16, 0.0), 0.2)
    result = execute_skill(world, "insert", np.array([0.0, GRASP_TO_TIP - 0.025, 0.0]))
    truth = world.ground_truth()
    assert result.reached and not result.compression_limit
    assert truth.success and truth.tip_depth_mm == pytest.approx(25.0, abs=1.0)
    _no_warnings(world)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("offset_mm", [5.0, -5.0])
def test_peg_offset_5mm_cannot_go_in(shape: str, offset_mm: float) -> None:
    """5 mm off the axis (4 mm over the rim with 1 mm radial clearance, no chamfer): the peg
    lands on the board and the compression limit stops the push."""
    y = offset_mm * MM
    world = _world(shape)
    _hold(world, (y, 0.16, 0.0), 0.2)
    result = execute_skill(world, "insert", np.array([y, GRASP_TO_TIP - 0.025, 0.0]))
    truth = world.ground_truth()
    assert result.compression_limit
    assert not truth.success and truth.tip_depth_mm < 1.0
    _no_warnings(world)


@pytest.mark.parametrize("shape", ["round", "rectangle"])
def test_hole_offset_moves_the_hole_and_ground_truth_follows(shape: str) -> None:
    """The pose condition's hole offset moves the physical hole: straight above the shifted
    hole goes in (offset ~0 in ground truth); straight above the nominal place does not."""
    hole_y = 12.0
    world = _world(shape, hole_y_mm=hole_y)
    _hold(world, (hole_y * MM, 0.16, 0.0), 0.2)
    execute_skill(world, "insert", np.array([hole_y * MM, GRASP_TO_TIP - 0.025, 0.0]))
    truth = world.ground_truth()
    assert truth.success and truth.inside_hole and abs(truth.tip_offset_mm) < 0.5
    world = _world(shape, hole_y_mm=hole_y)
    _hold(world, (0.0, 0.16, 0.0), 0.2)
    result = execute_skill(world, "insert", np.array([0.0, GRASP_TO_TIP - 0.025, 0.0]))
    truth = world.ground_truth()
    assert result.compression_limit and not truth.success
    assert truth.tip_offset_mm == pytest.approx(-hole_y, abs=1.0)


def test_ground_truth_needs_the_tip_inside_the_opening() -> None:
    """Scoring: deep but outside the opening (e.g. a tip pushed below z=0 off the hole) is no success."""
    world = _world("round")
    hole = world.hole
    mocap = world.model.body_mocapid[_body(world, "base")]
    for y, z, inside in ((0.0, -0.02, True), (hole.y_range[1] * 0.9, -0.02, True), (hole.y_range[1] + 0.002, -0.02, False),
                         (0.0, 0.005, False)):
        world.data.mocap_pos[mocap] = (0.0, y, z + GRASP_TO_TIP)
        world.data.qpos[:] = 0.0
        mujoco.mj_kinematics(world.model, world.data)
        truth = world.ground_truth()
        assert truth.inside_hole is inside and truth.success is inside, (y, z, truth)
        assert truth.tip_depth_mm == pytest.approx(-z / MM, abs=1e-6)


# --- conditions ----------------------------------------------------------

def test_friction_condition_scales_board_friction_only() -> None:
    params = sample_params(CFG, "round", "friction", seed=3)
    lo, hi = CFG.hole.friction_scale
    assert lo <= params.friction_scale <= hi and params.friction_scale != pytest.approx(1.0, abs=0.05)
    assert params.hole_y_mm == 0.0 and params.grasp_angle_deg == 0.0
    nominal, scaled = _world("round"), PegWorld(CFG, params)
    board = _body(scaled, "board")
    on_board = [g for g in range(scaled.model.ngeom) if scaled.model.geom_bodyid[g] == board]
    assert len(on_board) > 5
    for g in range(scaled.model.ngeom):
        mu, mu0 = scaled.model.geom_friction[g], nominal.model.geom_friction[g]
        if g in on_board:
            assert mu[0] == pytest.approx(CFG.hole.friction * params.friction_scale)
            assert mu[0] == pytest.approx(mu0[0] * params.friction_scale)
        else:
            assert mu[0] == mu0[0]
        assert np.array_equal(mu[1:], mu0[1:])  # torsional/rolling untouched


def test_friction_range_override_reaches_the_model() -> None:
    from kintsugi.config import apply_overrides

    cfg = apply_overrides(CFG, ["hole.friction_scale=[3,3]"])
    world = PegWorld(cfg, sample_params(cfg, "square", "all", seed=0))
    board = _body(world, "board")
    mus = [float(world.model.geom_friction[g, 0]) for g in range(world.model.ngeom)
           if world.model.geom_bodyid[g] == board]
    assert mus and all(mu == pytest.approx(3 * cfg.hole.friction) for mu in mus)


# --- the taught task -----------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_baseline_inserts_every_shape_in_the_default_condition(shape: str) -> None:
    record = run_trial(TrialSpec(task="peg-insertion", method="baseline", variant=shape, condition="none", seed=0))
    assert record.error is None, record.error
    assert record.success, record.params
    assert record.params["tip_depth_mm"] >= 10.0
    assert record.framework_success
