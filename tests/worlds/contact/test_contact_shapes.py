"""Objects beyond boxes: a part's volume, bounds, lowest point and surface follow its shape (cylinder, sphere,
capsule, two-part), MuJoCo simulates the shape the known model describes, and a declared section draws it.

Checks against independent references: dense samples of each solid's surface (numpy), MuJoCo's own masses from
the shape's volume, and objects dropped in the real simulation settling with their lowest point on the table.
"""

from __future__ import annotations

import math

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest
from pydantic import ValidationError

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import ContactConfig, FixtureSection, MarkerSection, ObjectSection
from kintsugi.worlds.contact.declare import declared_setup
from kintsugi.worlds.contact.objects import Geometry, Part, Physics, Placement, board, box, capsule, cylinder, sphere
from kintsugi.worlds.contact.spec import lowest_z
from kintsugi.worlds.contact.world import EvaluationWorld, Scene

RGBA = (0.5, 0.5, 0.5, 1.0)
SHAPES = {
    "box": box((0.05, 0.08, 0.03), RGBA),
    "cylinder-standing": cylinder(0.06, 0.03, RGBA),
    "cylinder-lying": cylinder(0.05, 0.11, RGBA, axis="y"),
    "sphere": sphere(0.05, RGBA),
    "capsule": capsule(0.04, 0.12, RGBA, axis="x"),
    "board": board((0.2, 0.16), (0.1, 0.05), 0.02, RGBA),
}


def _surface_points(part: Part, n: int = 4000) -> np.ndarray:
    """Points on (and, for a box, spanning) the part's surface, object frame, by rejection-free sampling."""
    rng = np.random.default_rng(0)
    if part.shape == "box":
        return np.asarray(part.pos) + rng.choice([-1.0, 1.0], size=(n, 3)) * np.asarray(part.half)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    if part.shape == "sphere":
        return np.asarray(part.pos) + part.half[0] * u
    i = "xyz".index(part.axis)
    r, hl = part.radius, part.half[i]
    if part.shape == "capsule":
        p = r * u
        p[:, i] += np.where(u[:, i] >= 0, hl - r, -(hl - r))
        return np.asarray(part.pos) + p
    theta = rng.uniform(0, 2 * math.pi, n)
    rim = np.zeros((n, 3))
    others = [k for k in range(3) if k != i]
    rim[:, others[0]], rim[:, others[1]] = r * np.cos(theta), r * np.sin(theta)
    rim[:, i] = rng.choice([-hl, hl], n)
    return np.asarray(part.pos) + rim


def _random_quats(n: int) -> np.ndarray:
    q = np.random.default_rng(1).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


@pytest.mark.parametrize("name", list(SHAPES))
def test_bounds_and_lowest_point_follow_the_shape_under_any_rotation(name: str) -> None:
    geo = SHAPES[name]
    pts = np.concatenate([_surface_points(p) for p in geo.parts])
    quats = _random_quats(20)
    pos = np.array([0.1, -0.05, 0.2])
    lo, hi = geo.bounds(np.broadcast_to(pos, (20, 3)), quats)
    for k, q in enumerate(quats):
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, q)
        world = pos + pts @ rot.reshape(3, 3).T
        # sampled points never beyond the bounds, and the bounds no looser than the sampling's resolution
        assert np.all(world.min(axis=0) >= lo[k] - 1e-9) and np.all(world.max(axis=0) <= hi[k] + 1e-9)
        assert np.allclose(world.min(axis=0), lo[k], atol=2.5e-3) and np.allclose(world.max(axis=0), hi[k], atol=2.5e-3)
    assert np.allclose(geo.lowest_z(pos, quats[0]), lo[0, 2])


def test_a_lying_cylinder_is_not_treated_as_its_box() -> None:
    geo = SHAPES["cylinder-lying"]
    turned = np.array([math.cos(math.pi / 8), math.sin(math.pi / 8), 0.0, 0.0])  # rolled 45 degrees about x
    lo, _ = geo.bounds(np.zeros(3), turned)
    r, hl = geo.parts[0].radius, geo.parts[0].half[1]
    # its rotated bounding box would reach (r + hl) sin 45 + ... below; the cylinder itself only r cos 0 + hl sin 45
    assert lo[2] == pytest.approx(-(hl * math.sin(math.pi / 4) + r * math.cos(math.pi / 4)), abs=1e-9)
    rolled = np.array([math.cos(math.pi / 8), 0.0, math.sin(math.pi / 8), 0.0])  # about its own axis? no: about y
    assert geo.bounds(np.zeros(3), rolled)[0][2] == pytest.approx(-r, abs=1e-9)  # a roll about its axis keeps it on r


def test_volumes_follow_the_shape() -> None:
    assert SHAPES["cylinder-standing"].volumes[0] == pytest.approx(math.pi * 0.03 ** 2 * 0.03)
    assert SHAPES["sphere"].volumes[0] == pytest.approx(4 / 3 * math.pi * 0.025 ** 3)
    assert SHAPES["capsule"].volumes[0] == pytest.approx(math.pi * 0.02 ** 2 * 0.08 + 4 / 3 * math.pi * 0.02 ** 3)
    assert SHAPES["board"].volumes == pytest.approx([0.2 * 0.16 * 0.02, 0.1 * 0.05 * 0.02])


@pytest.mark.parametrize("name", list(SHAPES))
def test_surface_distance_is_zero_on_the_surface_and_signed(name: str) -> None:
    geo = SHAPES[name]
    for part in geo.parts:
        pts = _surface_points(part, 200)
        assert max(abs(geo.surface_distance(p)) for p in pts) < 1e-9
    assert geo.surface_distance(geo.parts[0].pos) < 0
    assert geo.surface_distance(np.array([0.0, 0.0, 0.5])) > 0.4


def _world(geometry: dict[str, Geometry], start: dict[str, Placement]) -> EvaluationWorld:
    cfg = ContactConfig()
    physics = {k: Physics(mass_kg=0.2, friction=0.5) for k in geometry}
    return EvaluationWorld(cfg, Scene(geometry=geometry, start=start), physics)


def test_mujoco_simulates_the_declared_shapes_resting_at_their_lowest_point() -> None:
    names = [n for n in SHAPES if n != "board"]
    geometry = {n.replace("-", "_"): SHAPES[n] for n in names}
    start = {k: Placement(x=-0.2 + 0.1 * i, y=0.15) for i, k in enumerate(geometry)}
    world = _world(geometry, start)
    types = {mujoco.mjtGeom(world.model.geom_type[world.layout.obj_geoms[k][0]]).name for k in geometry}
    assert types == {"mjGEOM_BOX", "mjGEOM_CYLINDER", "mjGEOM_SPHERE", "mjGEOM_CAPSULE"}
    for k, geo in geometry.items():  # MuJoCo's mass is the declared one, its size the known model's
        assert world.model.body_mass[world.layout.obj_body[k]] == pytest.approx(0.2)
    # tilt every object and drop it from 5 cm: it settles with its lowest point on the table top
    for i, k in enumerate(geometry):
        a = world.layout.obj_qpos[k]
        world.data.qpos[a + 2] += 0.05
        q = np.array([math.cos(0.2 + 0.1 * i), math.sin(0.2 + 0.1 * i), 0.0, 0.0])
        world.data.qpos[a + 3:a + 7] = q
    world.step(1500)
    for k in geometry:
        assert -0.002 < lowest_z(world, k) < 0.002, (k, lowest_z(world, k))
        lo, hi = geometry[k].bounds(*world.object_pose(k))
        assert hi[2] > lo[2] + 0.02


def test_a_lying_cylinder_rolls_where_a_box_slides() -> None:
    geometry = {"can": SHAPES["cylinder-lying"], "block": box((0.05, 0.11, 0.05), RGBA)}
    world = _world(geometry, {"can": Placement(x=0.0, y=0.12), "block": Placement(x=0.0, y=-0.12)})
    for k in geometry:
        world.data.qvel[world.layout.obj_dof[k]] = 0.4  # both set moving along +x at 0.4 m/s
    world.step(50)
    can_spin = abs(world.object_velocity("can")[1][1])
    assert can_spin > 5.0 and abs(world.object_velocity("block")[1][1]) < 1.0  # rolling about its axis (y)
    world.step(2500)
    assert np.linalg.norm(world.object_velocity("can")[0]) < 0.01  # rolling resistance brings it to rest
    assert world.object_pose("can")[0][0] > world.object_pose("block")[0][0] + 0.02  # it rolled further


def test_an_unknown_shape_or_colour_is_a_clear_error() -> None:
    with pytest.raises(ValidationError, match="unknown shape 'cone'; known: box, cylinder, sphere, capsule"):
        Part(half=(0.1, 0.1, 0.1), shape="cone")
    with pytest.raises(ValidationError, match="unknown shape 'cone'; known: box, cylinder, capsule, sphere, board"):
        ObjectSection(shape="cone", size_m=((0.1, 0.1),), mass_kg=(1, 1), friction=(1, 1), x_m=(0, 0), y_m=(0, 0))
    with pytest.raises(ValidationError, match="a cylinder's size_m lists 2 ranges"):
        ObjectSection(shape="cylinder", size_m=((0.1, 0.1),), mass_kg=(1, 1), friction=(1, 1), x_m=(0, 0), y_m=(0, 0))
    with pytest.raises(ValidationError, match="unknown colour 'teal'"):
        ObjectSection(colour="teal", size_m=((0.1, 0.1),) * 3, mass_kg=(1, 1), friction=(1, 1), x_m=(0, 0), y_m=(0, 0))
    with pytest.raises(ValidationError, match="one radius across its axis"):
        Part(half=(0.02, 0.03, 0.05), shape="cylinder")


class _Declared(ContactConfig):
    ball: ObjectSection = ObjectSection(shape="sphere", label="foam ball", material="foam", colour="yellow",
                                        size_m=((0.05, 0.07),), mass_kg=(0.01, 0.03), friction=(0.5, 0.7),
                                        x_m=(0.0, 0.05), y_m=(-0.05, 0.05))
    tube: ObjectSection = ObjectSection(shape="capsule", axis="y", size_m=((0.03, 0.04), (0.10, 0.12)),
                                        mass_kg=(0.1, 0.2), friction=(0.4, 0.6), x_m=(-0.1, -0.05), y_m=(0.1, 0.12))
    post: FixtureSection = FixtureSection(size_m=(0.04, 0.04, 0.1), x_m=(0.15, 0.2), y_m=(0.0, 0.0), label="grey post")
    goal: MarkerSection = MarkerSection(x_m=(0.2, 0.25), y_m=(-0.1, -0.05), radius_m=0.03)


def test_declared_sections_become_the_scene_with_labels_and_hidden_physics() -> None:
    cfg = _Declared()
    a = declared_setup(cfg, Drawer("random", 4))
    ball, tube = a.scene.geometry["ball"], a.scene.geometry["tube"]
    assert (ball.shape, ball.label, ball.material, ball.colour) == ("sphere", "foam ball", "foam", "yellow")
    assert tube.label == "tube" and tube.parts[0].axis == "y" and tube.rest_z == pytest.approx(tube.parts[0].radius)
    assert a.scene.fixtures["post"].label == "grey post" and a.scene.markers["goal"].label == "goal"
    assert a.scene.fixtures["post"].pos[2] == pytest.approx(0.05)
    assert set(a.truth) == {"ball", "tube"} and 0.01 <= a.truth["ball"].mass_kg <= 0.03
    # the scene a method is shown holds no mass or friction; every draw is in the record's params
    assert "mass" not in a.scene.model_dump_json() and "friction" not in a.scene.model_dump_json()
    assert {"ball.diameter_m", "tube.length_m", "post.x_m", "goal.y_m", "ball.mass_kg"} <= set(a.params)
    b = declared_setup(cfg, Drawer("random", 5))
    assert a.params != b.params
    assert declared_setup(cfg, Drawer("none", 4)).params == declared_setup(cfg, Drawer("none", 9)).params
    with pytest.raises(ConfigError, match="declares no object"):
        declared_setup(ContactConfig(), Drawer("none", 0))
