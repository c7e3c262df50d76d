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

from kintsugi.core.plugins import load_builtins
from kintsugi.worlds.peg.conditions import sample_params
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.scene import WALL_THICK
from kintsugi.worlds.peg.shapes import MM, hole_for, peg_shape
from kintsugi.worlds.peg.skills import execute_skill
from kintsugi.worlds.peg.world import PegWorld, TrialParams
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial
from tests.sim_checks import assert_no_warnings

load_builtins()  # run_trial looks the task up in the registry

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
    assert_no_warnings(world)


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
    assert_no_warnings(world)


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
    assert_no_warnings(world)


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
    assert_no_warnings(world)


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
    assert_no_warnings(world)


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
    assert_no_warnings(world)


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


def _place(world: PegWorld, y: float, z: float, roll_deg: float = 0.0, x: float = 0.0) -> None:
    """Put the peg tip kinematically at (x, y, z) (rigid wrist) with the base rolled by roll_deg."""
    mocap = world.model.body_mocapid[_body(world, "base")]
    roll = math.radians(roll_deg)
    world.data.mocap_quat[mocap] = (math.cos(roll / 2), math.sin(roll / 2), 0, 0)
    world.data.qpos[:] = 0.0
    world.data.mocap_pos[mocap] = (0.0, 0.0, 0.0)
    mujoco.mj_kinematics(world.model, world.data)
    tip = world.data.site_xpos[mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_SITE, "peg_tip")].copy()
    world.data.mocap_pos[mocap] = (x - tip[0], y - tip[1], z - tip[2])
    mujoco.mj_kinematics(world.model, world.data)


def test_ground_truth_needs_depth_inside_the_footprint_and_an_upright_peg() -> None:
    """Scoring (kinematic poses): the tip >= half the hole depth (20 mm) below the top, inside the
    opening's footprint along x and y, and the axis within atan(clearance / 20 mm) = 5.71 deg."""
    world = _world("round", hole_x_mm=3.0)
    hole = world.hole
    edge = hole.y_range[1]
    bound = math.degrees(math.atan2(CFG.peg.clearance_mm, 20.0))
    cases = [  # (y, z, roll, x, inside, success)
        (0.0, -0.0205, 0.0, 0.003, True, True),
        (0.0, -0.0195, 0.0, 0.003, True, False),  # 19.5 mm: inside, too shallow (old G passed >= 10 mm)
        (0.0, -0.012, 0.0, 0.003, True, False),
        (edge * 0.9, -0.025, 0.0, 0.003, True, True),
        (edge + 0.002, -0.025, 0.0, 0.003, False, False),  # beyond the opening along y
        (0.0, -0.025, 0.0, 0.003 + edge + 0.002, False, False),  # beyond it along x (hole moved to x = 3 mm)
        (0.0, -0.025, 0.0, 0.0, True, True),  # 3 mm off along x is still inside
        (0.0, 0.005, 0.0, 0.003, False, False),
        (0.0, -0.025, bound - 0.1, 0.003, True, True),
        (0.0, -0.025, bound + 0.1, 0.003, True, False),  # wedged: tilted past the rigid bound
        (0.0, -0.025, -(bound + 0.1), 0.003, True, False),
    ]
    for y, z, roll, x, inside, success in cases:
        _place(world, y, z, roll, x)
        truth = world.ground_truth()
        assert (truth.inside_hole, truth.success) == (inside, success), (y, z, roll, x, truth)
        assert truth.tip_depth_mm == pytest.approx(-z / MM, abs=1e-6)
        assert truth.tilt_deg == pytest.approx(abs(roll), abs=1e-6)
        assert truth.tip_offset_x_mm == pytest.approx((x - 0.003) / MM, abs=1e-6)
        assert truth.max_tilt_deg == pytest.approx(bound, abs=1e-6)


def test_tilt_bound_follows_the_lean_direction_and_the_config() -> None:
    """A square leaning along its diagonal has sqrt(2) x the clearance; a configured bound wins."""
    world = _world("square")
    flats = math.degrees(math.atan2(2.0, 20.0))
    assert world.max_tilt_deg((0.0, 1.0)) == pytest.approx(flats, abs=1e-6)
    assert world.max_tilt_deg((1.0, 0.0)) == pytest.approx(flats, abs=1e-6)
    diagonal = (math.sqrt(0.5), math.sqrt(0.5))
    assert world.max_tilt_deg(diagonal) == pytest.approx(math.degrees(math.atan2(2.0 * math.sqrt(2), 20.0)), abs=1e-3)
    from kintsugi.core.config import apply_overrides

    cfg = apply_overrides(CFG, ["scoring.max_tilt_deg=3", "scoring.min_depth_fraction=0.75"])
    world = PegWorld(cfg, TrialParams(shape="square"))
    assert world.max_tilt_deg(diagonal) == 3.0
    _place(world, 0.0, -0.029, 2.0)
    assert not world.ground_truth().success  # 29 mm < 0.75 x 40 mm
    _place(world, 0.0, -0.031, 2.0)
    assert world.ground_truth().success
    _place(world, 0.0, -0.031, 3.5)
    assert not world.ground_truth().success


def _run_taught(world: PegWorld) -> None:
    from kintsugi.worlds.peg.goals import full_goals, load_goals
    from kintsugi.worlds.peg.skills import SEQUENCE
    from kintsugi.worlds.peg.world import HOME_POSE

    targets = full_goals(load_goals(), HOME_POSE)
    for skill in SEQUENCE:
        execute_skill(world, skill, targets[skill])


@pytest.mark.parametrize(("shape", "hole_y", "angle", "shallow"), [
    ("square", 17.72, 0.11, True),  # condition pose, seed 4: jammed 16.9 mm deep at 8.7 deg
    ("round", -18.0, 0.06, False),  # condition pose, seed 29: 20.5 mm deep but wedged at 7.4 deg
])
def test_jammed_tilted_peg_is_not_a_success(shape: str, hole_y: float, angle: float, shallow: bool) -> None:
    """The taught goals against a displaced hole wedge the peg between the rim and the far wall.
    The baseline's own verdict is success and the old G (tip >= 10 mm in the hole) said so too."""
    world = _world(shape, hole_y_mm=hole_y, grasp_angle_deg=angle)
    _run_taught(world)
    truth = world.ground_truth()
    assert truth.inside_hole and truth.tip_depth_mm >= 10.0  # what the old G accepted
    assert truth.tilt_deg > truth.max_tilt_deg + 1.0
    assert (truth.tip_depth_mm < truth.min_depth_mm) is shallow
    assert not truth.success
    assert_no_warnings(world)


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
    from kintsugi.core.config import apply_overrides

    cfg = apply_overrides(CFG, ["hole.friction_scale=[3,3]"])
    world = PegWorld(cfg, sample_params(cfg, "square", "all", seed=0))
    board = _body(world, "board")
    mus = [float(world.model.geom_friction[g, 0]) for g in range(world.model.ngeom)
           if world.model.geom_bodyid[g] == board]
    assert mus and all(mu == pytest.approx(3 * cfg.hole.friction) for mu in mus)


# --- the taught task -----------------------------------------------------

@pytest.mark.parametrize("shape", SHAPES)
def test_baseline_inserts_every_shape_in_the_default_condition(shape: str) -> None:
    """The taught goals in the default condition: a G success, deep, centred and upright, each with
    margin (so the taught goals are not marginal under G)."""
    record = run_trial(TrialSpec(task="peg-insertion", method="baseline", variant=shape, condition="none", seed=0))
    assert record.error is None, record.error
    assert record.success, record.params
    p = record.params
    assert p["tip_depth_mm"] >= 20.0 + 3.0  # G needs half the 40 mm hole
    assert p["tilt_deg"] < math.degrees(math.atan2(CFG.peg.clearance_mm, 20.0)) / 3
    assert abs(p["tip_offset_mm"]) < 2.0 and abs(p["tip_offset_x_mm"]) < 0.5
    assert record.framework_success
