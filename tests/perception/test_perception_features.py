"""Object features from real MuJoCo seg+depth renders, scored against the scene's ground truth.

The scene: a table plane, an upright cylinder (bottle), a lying cylinder, a
leaning cylinder and a box, seen by a top and a front camera at 320x240.
"""

from __future__ import annotations

import math

import kintsugi  # noqa: F401  (sets MUJOCO_GL before mujoco loads)
import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from kintsugi.core.errors import ConfigError, UnknownNameError
from kintsugi.perception.features import (
    CameraModel,
    FeatureConfig,
    ObjectFeatures,
    Primitive,
    body_geom_ids,
    features,
    object_cloud,
    object_clouds,
    SegDepthRenderer,
    render_view,
    see_through,
)
from kintsugi.perception.primitives import Fit
from kintsugi.perception.sdf import box_sdf, box_tray_sdf, cylinder_cup_sdf, cylinder_sdf, sphere_sdf

W, H = 320, 240


def cup_xml(r: float, h: float, wall: float, walls: int = 16) -> str:
    """A hollow cup: a floor disc and a ring of thin boxes, open at the top."""
    half_w = (r - wall / 2) * math.tan(math.pi / walls) + 0.001
    out = f'<geom type="cylinder" size="{r} {wall / 2}" pos="0 0 {-h + wall / 2}"/>'
    for k in range(walls):
        a = 2 * math.pi * k / walls
        x, y = (r - wall / 2) * math.cos(a), (r - wall / 2) * math.sin(a)
        out += f'<geom type="box" size="{wall / 2} {half_w} {h - wall / 2}" pos="{x} {y} {wall / 2}" euler="0 0 {math.degrees(a)}"/>'
    return out


def tray_xml(hx: float, hy: float, hz: float, wall: float) -> str:
    """A tray: a base plate and four rims, open at the top."""
    out = f'<geom type="box" size="{hx} {hy} {wall / 2}" pos="0 0 {-hz + wall / 2}"/>'
    for sx, sy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        size = (wall / 2, hy, hz) if sx else (hx, wall / 2, hz)
        out += f'<geom type="box" size="{size[0]} {size[1]} {size[2]}" pos="{sx * (hx - wall / 2)} {sy * (hy - wall / 2)} 0"/>'
    return out


SCENE = f"""
<mujoco>
  <visual><global offwidth="{W}" offheight="{H}"/></visual>
  <worldbody>
    <geom name="table" type="plane" size="1 1 0.01"/>
    <body name="bottle" pos="0.06 0.03 0.11"><geom type="cylinder" size="0.035 0.11"/></body>
    <body name="lying" pos="-0.12 0.12 0.03" euler="0 90 30"><geom type="cylinder" size="0.03 0.08"/></body>
    <body name="leaning" pos="-0.05 -0.15 0.08" euler="0 25 0"><geom type="cylinder" size="0.025 0.07"/></body>
    <body name="block" pos="0.14 -0.1 0.025" euler="0 0 25"><geom type="box" size="0.04 0.025 0.025"/></body>
    <body name="hidden" pos="3 3 0.05"><geom type="sphere" size="0.03"/></body>
    <body name="cup" pos="-0.17 -0.03 0.05" euler="0 0 10">{cup_xml(0.04, 0.05, 0.004)}</body>
    <body name="tray" pos="0.14 0.16 0.012" euler="0 0 -15">{tray_xml(0.08, 0.06, 0.012, 0.006)}</body>
    <camera name="top" pos="0 0 0.9" xyaxes="1 0 0 0 1 0" fovy="50"/>
    <camera name="front" pos="0.75 0 0.45" xyaxes="0 1 0 -0.5 0 0.866" fovy="50"/>
  </worldbody>
</mujoco>"""
PRIMITIVES = {
    "bottle": Primitive.cylinder(0.035, 0.11),
    "lying": Primitive.cylinder(0.03, 0.08),
    "leaning": Primitive.cylinder(0.025, 0.07),
    "block": Primitive.box(0.04, 0.025, 0.025),
    "cup": Primitive.cylinder(0.04, 0.05, wall=0.004),
    "tray": Primitive.box(0.08, 0.06, 0.012, wall=0.006),
}
AXIS_COLUMN = {"bottle": 2, "lying": 2, "leaning": 2, "block": 0, "cup": 2, "tray": 0}  # which body axis is the object's axis


class Scene:
    def __init__(self) -> None:
        self.model = mujoco.MjModel.from_xml_string(SCENE)
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        with mujoco.Renderer(self.model, H, W) as renderer:
            self.views = [render_view(renderer, self.data, cam) for cam in ("top", "front")]
        self.ids = {name: body_geom_ids(self.model, name) for name in [*PRIMITIVES, "hidden"]}
        self.ids["table"] = {mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "table")}
        self.clouds = object_clouds(self.views, self.ids)
        self.feats = {name: features(name, self.clouds[name], prim, views=self.views) for name, prim in PRIMITIVES.items()}

    def truth(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Ground truth (scoring only): body centre and the object's axis."""
        bid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
        return self.data.xpos[bid].copy(), self.data.xmat[bid].reshape(3, 3)[:, AXIS_COLUMN.get(name, 2)].copy()


@pytest.fixture(scope="module")
def scene() -> Scene:
    return Scene()


def points_up(axis) -> bool:
    """The sign convention: up, or within 2 deg of horizontal and towards +x (then +y)."""
    level = math.sin(math.radians(2.0))
    if abs(axis[2]) > level:
        return axis[2] > 0
    return axis[0] > 0 if abs(axis[0]) > level else axis[1] > 0


def angle_deg(a, b) -> float:
    """Angle between two lines (sign-free)."""
    c = abs(float(np.dot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(min(1.0, c)))


# --- camera model against known geometry ----------------------------------------------------


def test_depth_is_z_depth_not_ray_length(scene: Scene) -> None:
    cam, depth, seg = scene.views[0]
    table = seg[..., 0] == 0
    assert table[0, 0] and table[H // 2, 0]  # corners of the top view see the table
    # The top camera is 0.9 m above the table plane and looks straight down: z-depth is 0.9 everywhere,
    # while the ray length grows to 0.9 / cos(angle) (about 1.03 m in the corner).
    assert np.allclose(depth[table], 0.9, atol=2e-4)
    assert cam.points(depth)[0, 0, 2] == pytest.approx(0.0, abs=2e-4)


@pytest.mark.parametrize("view", [0, 1])
def test_table_pixels_back_project_onto_the_table_plane(scene: Scene, view: int) -> None:
    cam, depth, seg = scene.views[view]
    pts = cam.points(depth)[seg[..., 0] == 0]
    assert len(pts) > 10_000
    assert np.abs(pts[:, 2]).max() < 1e-3  # the oblique front view checks fovy, pixel centres and orientation


def test_project_inverts_points(scene: Scene) -> None:
    cam, depth, _ = scene.views[1]
    rows, cols = np.mgrid[0:H:17, 0:W:23]
    pix = cam.project(cam.points(depth)[rows, cols].reshape(-1, 3))
    assert np.allclose(pix, np.stack([cols.ravel() + 0.5, rows.ravel() + 0.5], axis=1), atol=1e-6)


def test_cloud_lies_on_the_true_surface(scene: Scene) -> None:
    centre, axis = scene.truth("bottle")
    v = scene.clouds["bottle"] - centre
    radial = np.linalg.norm(v - np.outer(v @ axis, axis), axis=1)
    side = np.abs(v @ axis) < 0.1
    assert side.sum() > 300
    # MuJoCo draws a cylinder as a polygon, so side points sit slightly inside the true radius.
    assert np.all(np.abs(radial[side] - 0.035) < 1.5e-3)


def test_one_pass_renderer_matches_mujoco_renderer(scene: Scene) -> None:
    with SegDepthRenderer(scene.model, W, H) as renderer:
        for two_pass, cam in zip(scene.views, ("top", "front")):
            one_pass = render_view(renderer, scene.data, cam)
            assert np.array_equal(one_pass.seg, two_pass.seg)
            assert np.array_equal(one_pass.depth, two_pass.depth)
            assert np.array_equal(one_pass.camera.xmat, two_pass.camera.xmat)
    with pytest.raises(ConfigError, match="after close"):
        renderer.view(scene.data, "top")
    with pytest.raises(ConfigError, match="offscreen buffer"):
        SegDepthRenderer(scene.model, 2 * W, H)


# --- features on the rendered scene -------------------------------------------------------


@pytest.mark.parametrize("name", list(PRIMITIVES))
def test_fit_removes_the_one_sided_bias(scene: Scene, name: str) -> None:
    f = scene.feats[name]
    centre, _ = scene.truth(name)
    assert f.visible and f.fit == "primitive", f.note
    raw_err = np.linalg.norm(np.array(f.raw_centroid) - centre)  # biased towards the cameras
    fit_err = np.linalg.norm(np.array(f.centroid) - centre)
    assert raw_err > 0.003 and fit_err < 0.001 and fit_err < raw_err / 4
    assert f.fit_rms is not None and f.fit_rms < 1e-3 and f.fit_inliers > 0.95


@pytest.mark.parametrize("name", list(PRIMITIVES))
def test_axis_and_uprightness(scene: Scene, name: str) -> None:
    f = scene.feats[name]
    _, axis = scene.truth(name)
    assert angle_deg(f.axis, axis) < 2.0
    assert np.linalg.norm(f.axis) == pytest.approx(1.0)
    assert points_up(f.axis)
    expected_tilt = math.degrees(math.acos(abs(axis[2])))
    assert f.tilt_deg == pytest.approx(expected_tilt, abs=2.0)
    assert f.upright is (name in ("bottle", "cup"))


def test_extremes(scene: Scene) -> None:
    bottle = scene.feats["bottle"]
    centre, _ = scene.truth("bottle")
    assert np.allclose(bottle.extremes["top"], centre + [0, 0, 0.11], atol=2e-3)  # the cap's centre
    assert np.allclose(bottle.extremes["bottom"], centre - [0, 0, 0.11], atol=2e-3)
    assert np.allclose(bottle.extremes["axis_pos"], bottle.extremes["top"], atol=1e-9)
    assert np.allclose(bottle.along(0.75), centre + [0, 0, 0.055], atol=2e-3)  # three quarters up the bottle
    lying = scene.feats["lying"]
    centre, axis = scene.truth("lying")
    ends = sorted([lying.extremes["axis_pos"], lying.extremes["axis_neg"]])
    truth = sorted([tuple(centre + 0.08 * axis), tuple(centre - 0.08 * axis)])
    assert np.allclose(ends, truth, atol=2e-3)
    assert np.allclose(lying.extremes["top"], centre + [0, 0, 0.03], atol=2e-3)
    block = scene.feats["block"]
    centre, _ = scene.truth("block")
    assert np.allclose(block.extremes["top"], centre + [0, 0, 0.025], atol=2e-3)  # the top face's centre


def test_containers_fit_as_open_shells(scene: Scene) -> None:
    cup, tray = scene.feats["cup"], scene.feats["tray"]
    centre, _ = scene.truth("cup")
    assert np.allclose(cup.extremes["opening"], centre + [0, 0, 0.05], atol=2e-3)  # its mouth, wherever it points
    centre, _ = scene.truth("tray")
    assert np.allclose(tray.extremes["opening"], centre + [0, 0, 0.012], atol=2e-3)
    assert "opening" not in scene.feats["bottle"].extremes
    # As solids, the cameras see into them: the views check refuses the solid fit.
    solid_cup = features("cup", scene.clouds["cup"], Primitive.cylinder(0.04, 0.05), views=scene.views)
    assert solid_cup.fit == "raw" and solid_cup.note == "cylinder fit contradicts the views"
    solid_tray = features("tray", scene.clouds["tray"], Primitive.box(0.08, 0.06, 0.012), views=scene.views)
    assert solid_tray.fit == "raw" and solid_tray.note == "box fit contradicts the views"


def test_raw_features_without_a_known_shape(scene: Scene) -> None:
    f = features("bottle", scene.clouds["bottle"], None)
    centre, axis = scene.truth("bottle")
    assert f.fit == "raw" and f.note == "no known shape" and f.fit_rms is None
    assert f.centroid == f.raw_centroid
    assert angle_deg(f.axis, axis) < 10.0 and f.upright is True  # PCA of a cap plus one side leans towards the camera
    assert f.extremes["top"][2] == pytest.approx(0.22, abs=1e-3)  # topmost point is still exact
    top = np.array(f.extremes["top"])
    assert np.linalg.norm(top[:2] - centre[:2]) < 0.005  # the cap is seen whole from above


def test_a_single_view_is_biased_and_the_fit_fixes_it(scene: Scene) -> None:
    front = object_cloud(scene.views[1:], scene.ids["bottle"])
    f = features("bottle", front, PRIMITIVES["bottle"])
    centre, _ = scene.truth("bottle")
    raw_err = np.linalg.norm(np.array(f.raw_centroid)[:2] - centre[:2])
    assert raw_err > 0.02  # the probe saw 26-32 mm for a bottle
    assert np.linalg.norm(np.array(f.centroid) - centre) < 0.002


def test_wrong_shape_falls_back_to_raw(scene: Scene) -> None:
    f = features("block", scene.clouds["block"], Primitive.cylinder(0.01, 0.1))
    assert f.visible and f.fit == "raw" and "cylinder fit" in f.note
    assert f.centroid == f.raw_centroid
    assert features("bottle", scene.clouds["bottle"], Primitive.sphere(0.03)).fit == "raw"


def test_views_reject_a_shape_that_claims_seen_empty_space(scene: Scene) -> None:
    # A 20 cm cylinder can lay its cap and side on two faces of the block: the points alone accept it ...
    wrong = Primitive.cylinder(0.1, 0.1)
    assert features("block", scene.clouds["block"], wrong).fit == "primitive"
    # ... but both cameras see the table where that cylinder would be.
    f = features("block", scene.clouds["block"], wrong, views=scene.views)
    assert f.fit == "raw" and f.note == "cylinder fit contradicts the views"
    # A bottle seen from one end could extend either way from its cap; the cameras see through the wrong one.
    centre, _ = scene.truth("bottle")
    right = Fit("cylinder", centre, np.eye(3), np.array([0.035, 0.11, 0.0]), 0.0, 1.0)
    flipped = Fit("cylinder", centre + [0, 0, 0.22], np.eye(3), np.array([0.035, 0.11, 0.0]), 0.0, 1.0)
    assert see_through(right, scene.views[:1], FeatureConfig()) == 0.0
    assert see_through(flipped, scene.views[:1], FeatureConfig()) > 0.5
    for name, prim in PRIMITIVES.items():  # the right shapes pass the same check
        g = features(name, scene.clouds[name], prim, views=scene.views)
        assert g.fit == "primitive" and g.centroid == scene.feats[name].centroid


def test_too_few_points_for_a_fit(scene: Scene) -> None:
    f = features("bottle", scene.clouds["bottle"][:20], PRIMITIVES["bottle"])
    assert f.visible and f.fit == "raw" and "20 points" in f.note


def test_invisible_object_is_not_a_crash(scene: Scene) -> None:
    assert len(scene.clouds["hidden"]) == 0
    f = features("hidden", scene.clouds["hidden"], Primitive.sphere(0.03))
    assert not f.visible and f.n_points == 0 and f.centroid is None and f.axis is None and f.extremes == {}
    with pytest.raises(ConfigError, match="not visible"):
        f.along(0.5)
    assert not features("x", np.empty((0, 3))).visible
    assert not object_cloud(scene.views, {12345}).size


def test_features_are_finite_and_serialisable(scene: Scene) -> None:
    for f in scene.feats.values():
        values = [f.fit_rms, f.fit_inliers, f.tilt_deg, *f.centroid, *f.axis, *f.extent]
        values += [x for p in f.extremes.values() for x in p]
        assert np.all(np.isfinite(values))
        assert ObjectFeatures.model_validate_json(f.model_dump_json()) == f
    noisy = np.vstack([scene.clouds["bottle"], [[np.nan, 0, 0], [np.inf, 1, 1]]])
    assert features("bottle", noisy).n_points == len(scene.clouds["bottle"])


def test_one_pass_equals_per_object_and_is_bounded(scene: Scene) -> None:
    for name in PRIMITIVES:
        assert np.array_equal(object_cloud(scene.views, scene.ids[name]), scene.clouds[name])
    assert len(scene.clouds["table"]) == 2000
    assert len(object_cloud(scene.views, scene.ids["table"], max_points=50)) == 50
    geoms_only = [(v.camera, v.depth, np.where(v.seg[..., 1] == 5, v.seg[..., 0], -1)) for v in scene.views]
    assert np.array_equal(object_cloud(geoms_only, scene.ids["bottle"]), scene.clouds["bottle"])


def test_a_flying_pixel_is_left_out_and_every_real_pixel_kept(scene: Scene) -> None:
    """A lone silhouette pixel whose depth belongs to nothing near it (seen on a lying spoon: 12 cm above it)."""
    cam, depth, seg = scene.views[0]
    bottle = scene.ids["bottle"]
    assert len(object_cloud([(cam, depth, seg)], bottle, max_points=10**6, flying_tol_m=None)) == len(
        object_cloud([(cam, depth, seg)], bottle, max_points=10**6))  # a clean render has none
    rows, cols = np.nonzero(np.isin(np.where(seg[..., 1] == 5, seg[..., 0], -1), list(bottle)))
    planted = depth.copy()
    for k in (int(np.argmin(cols)), len(rows) // 2):  # on its silhouette (its wall seen edge-on), on its top
        planted[rows[k], cols[k]] = depth[rows[k] - 1:rows[k] + 2, cols[k] - 1:cols[k] + 2].min() - 0.12
    kept = object_cloud([(cam, planted, seg)], bottle, max_points=10**6)
    raw = object_cloud([(cam, planted, seg)], bottle, max_points=10**6, flying_tol_m=None)
    assert len(kept) == len(raw) - 2
    assert kept[:, 2].max() < raw[:, 2].max() - 0.05


def test_bad_inputs_name_the_problem(scene: Scene) -> None:
    cam, depth, seg = scene.views[0]
    with pytest.raises(ConfigError, match="depth image has shape"):
        cam.points(depth[:10])
    with pytest.raises(ConfigError, match="segmentation image has shape"):
        object_cloud([(cam, depth, seg[:5])], {1})
    with pytest.raises(ConfigError, match="belongs to both"):
        object_clouds(scene.views, {"a": {1}, "b": {1, 2}})
    with pytest.raises(UnknownNameError, match="cameras: top, front"):
        CameraModel.from_mujoco(scene.model, scene.data, "side", W, H)
    with pytest.raises(ConfigError, match="not a rotation"):
        CameraModel(W, H, 50.0, np.zeros(3), np.ones((3, 3)))
    with pytest.raises(ConfigError, match="shape"):
        features("bottle", np.zeros((5, 2)))
    with pytest.raises(ValidationError, match="needs radius"):
        Primitive(kind="cylinder")
    with pytest.raises(ValidationError, match="takes no radius"):
        Primitive(kind="box", half_extents=(0.1, 0.1, 0.1), radius=0.1)
    with pytest.raises(ValidationError):
        Primitive(kind="cone", radius=0.1)
    with pytest.raises(ValidationError, match="no cavity"):
        Primitive.cylinder(0.03, 0.05, wall=0.03)
    with pytest.raises(ValidationError, match="needs half_length"):
        Primitive.cylinder(0.03, wall=0.003)
    with pytest.raises(ValidationError, match="takes no wall"):
        Primitive(kind="sphere", radius=0.1, wall=0.01)


def test_body_geom_ids_include_child_bodies() -> None:
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom name="floor" type="plane" size="1 1 .1"/>'
        '<body name="tray"><geom name="base" size=".1 .1 .01" type="box"/>'
        '<body name="handle"><geom name="h" size=".01"/></body></body>'
        '<body name="cup"><geom name="c" size=".03"/></body></worldbody></mujoco>'
    )
    gid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n)  # noqa: E731
    assert body_geom_ids(model, "tray") == {gid("base"), gid("h")}
    assert body_geom_ids(model, "cup") == {gid("c")}
    with pytest.raises(UnknownNameError, match="mug"):
        body_geom_ids(model, "mug")


def test_unsupported_cameras_are_refused() -> None:
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><camera name="ortho" projection="orthographic" fovy="0.5"/>'
        '<camera name="sensor" sensorsize="0.01 0.01" focal="0.01 0.01" resolution="100 100"/></worldbody></mujoco>'
    )
    data = mujoco.MjData(model)
    with pytest.raises(ConfigError, match="orthographic"):
        CameraModel.from_mujoco(model, data, "ortho", W, H)
    with pytest.raises(ConfigError, match="sensorsize"):
        CameraModel.from_mujoco(model, data, "sensor", W, H)


# --- properties on synthetic clouds ---------------------------------------------------------

rotations = st.tuples(*[st.floats(-1.0, 1.0)] * 4).filter(lambda q: np.linalg.norm(q) > 0.2)
translations = st.tuples(*[st.floats(-0.5, 0.5)] * 3)


def rotation(q) -> np.ndarray:
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def cylinder_patch(seed: int, r: float, h: float, n: int = 400) -> np.ndarray:
    """Points on the side (half of it, as one camera sees it) and one cap of a cylinder along z at the origin."""
    rng = np.random.default_rng(seed)
    phi = rng.uniform(-math.pi / 2, math.pi / 2, n)
    side = np.column_stack([r * np.cos(phi), r * np.sin(phi), rng.uniform(-h, h, n)])
    rho, th = r * np.sqrt(rng.uniform(0, 1, n // 3)), rng.uniform(0, 2 * math.pi, n // 3)
    cap = np.column_stack([rho * np.cos(th), rho * np.sin(th), np.full(n // 3, h)])
    return np.vstack([side, cap])


@settings(max_examples=40, deadline=None, derandomize=True)
@given(q=rotations, t=translations, seed=st.integers(0, 10_000))
def test_raw_centroid_and_axis_are_equivariant(q, t, seed) -> None:
    rng = np.random.default_rng(seed)
    cloud = rng.normal(size=(500, 3)) * [0.1, 0.03, 0.01] + rng.uniform(-0.3, 0.3, 3)
    rot, t = rotation(q), np.asarray(t)
    a = features("a", cloud)
    b = features("b", cloud @ rot.T + t)
    assert np.allclose(b.centroid, rot @ a.centroid + t, atol=1e-9)
    assert angle_deg(b.axis, rot @ a.axis) < 1e-4
    assert np.allclose(b.extent, a.extent, atol=1e-9)
    assert points_up(b.axis)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(q=rotations, t=translations, seed=st.integers(0, 10_000))
def test_cylinder_fit_recovers_pose_and_is_equivariant(q, t, seed) -> None:
    rot, t = rotation(q), np.asarray(t)
    noise = np.random.default_rng(seed + 1).normal(scale=3e-4, size=(533, 3))
    cloud = (cylinder_patch(seed, 0.035, 0.1) + noise) @ rot.T + t
    f = features("c", cloud, Primitive.cylinder(0.035, 0.1))
    assert f.fit == "primitive", f.note
    assert np.linalg.norm(np.array(f.centroid) - t) < 1e-3
    assert np.linalg.norm(np.array(f.raw_centroid) - t) > 0.01
    assert angle_deg(f.axis, rot[:, 2]) < 1.0
    # Moving the cloud rigidly moves the fitted centre with it.
    rot2 = rotation((0.3, -0.2, 0.9, 0.1))
    g = features("c", cloud @ rot2.T + [0.1, -0.2, 0.05], Primitive.cylinder(0.035, 0.1))
    assert np.allclose(g.centroid, rot2 @ np.array(f.centroid) + [0.1, -0.2, 0.05], atol=5e-4)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(yaw=st.floats(-math.pi, math.pi), t=translations, seed=st.integers(0, 10_000))
def test_box_fit_recovers_centre_and_yaw(yaw, t, seed) -> None:
    he = np.array([0.05, 0.03, 0.02])
    rng = np.random.default_rng(seed)
    top = np.column_stack([rng.uniform(-he[0], he[0], 300), rng.uniform(-he[1], he[1], 300), np.full(300, he[2])])
    front = np.column_stack([np.full(150, he[0]), rng.uniform(-he[1], he[1], 150), rng.uniform(-he[2], he[2], 150)])
    side = np.column_stack([rng.uniform(-he[0], he[0], 150), np.full(150, he[1]), rng.uniform(-he[2], he[2], 150)])
    rot = rotation((math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)))
    cloud = np.vstack([top, front, side]) @ rot.T + t
    f = features("b", cloud, Primitive.box(*he))
    assert f.fit == "primitive", f.note
    assert np.linalg.norm(np.array(f.centroid) - t) < 1e-3
    assert angle_deg(f.axis, rot[:, 0]) < 1.0 and f.upright is False  # its long side lies flat


@pytest.mark.parametrize(
    "shape",
    ["cylinder", "infinite cylinder", "box", "cup", "tray", "sphere"],
)
def test_sdf_gradients_match_finite_differences(shape: str) -> None:
    """The fit's analytic Jacobian rests on these gradients; wherever the distance is smooth they must be exact."""
    he = np.array([0.05, 0.03, 0.02])
    sdf = {
        "cylinder": lambda x: cylinder_sdf(x, 0.03, 0.06),
        "infinite cylinder": lambda x: cylinder_sdf(x, 0.03, None),
        "box": lambda x: box_sdf(x, he),
        "cup": lambda x: cylinder_cup_sdf(x, 0.03, 0.05, 0.004),
        "tray": lambda x: box_tray_sdf(x, he, 0.005),
        "sphere": lambda x: sphere_sdf(x, 0.03),
    }[shape]
    x = np.random.default_rng(7).uniform(-0.08, 0.08, size=(2000, 3))
    d, g = sdf(x)
    eps = 1e-6
    fd = np.empty_like(x)
    smooth = np.ones(len(x), bool)
    for k in range(3):
        step = np.zeros(3)
        step[k] = eps
        plus, minus = sdf(x + step)[0], sdf(x - step)[0]
        fd[:, k] = (plus - minus) / (2 * eps)
        smooth &= np.abs((plus - d) - (d - minus)) < 1e-9  # one-sided slopes agree: no kink here
    assert smooth.mean() > 0.95
    assert np.allclose(g[smooth], fd[smooth], atol=1e-5)
    assert np.allclose(np.linalg.norm(g, axis=1), 1.0)
