"""Where object features come from: the one visible switch between perception and ground truth.

`perception.objects = "perceived"` (default): seg + depth renders of the top and front
cameras -> fused per-object clouds -> `kintsugi.perception.features` (centroid, PCA
axis, extremes, uprightness, fitted to the object's known primitive); a cloth (flex)
-> its cloud's centroid, PCA axis and four corners (`cloth.corner_features`).
`perception.objects = "truth"`: the same `ObjectFeatures`, computed from the
simulator's object poses (the paper's simulation setting), marked `note="ground truth"`.
"""

from __future__ import annotations

import math
from typing import Iterable

import mujoco
import numpy as np

from kintsugi.perception.features import ObjectFeatures, features, object_clouds, render_view, sign_normalized
from kintsugi.perception.primitives import Fit
from kintsugi.worlds.tabletop.cloth import CLOUD_POINTS, cloud_corners, corner_features, truth_corner_features
from kintsugi.worlds.tabletop.objects import CAP_HALF_M, Shape
from kintsugi.worlds.tabletop.scene import CAMERAS
from kintsugi.worlds.tabletop.world import GroundTruth, TabletopWorld

UP = np.array([0.0, 0.0, 1.0])
UPRIGHT_TOL_DEG = 15.0
MIN_CAP_POINTS = 10
"""Fewer cap pixels than this (hidden behind a hand) tell nothing about which end is the top."""
CAP_BELOW_M = 0.02
"""A cap this far below the object's centre: it stands on its head (a lying bottle's cap is level with it)."""


class ObjectPerception:
    def __init__(self, world: TabletopWorld) -> None:
        self._world = world
        self.mode = world.cfg.perception.objects
        self._geoms = {k: {int(g) for g in np.flatnonzero(world.geom_object == i)} for i, k in enumerate(world.objects)}
        self._caps = {k: {mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, f"{k}_cap")}
                      for k in world.objects if world.shapes[k].cap}
        """The painted cap of an object that has one: its pixels say which end is the top."""
        self._shapes = world.shapes
        cams = world.cfg.cameras
        self._pixel_m = 2 * cams.top_height_m * math.tan(math.radians(cams.top_fovy_deg) / 2) / cams.height
        """The top view's pixel footprint on the table (a cloth's corners are pixel-limited)."""

    def features(self, names: Iterable[str] | None = None) -> dict[str, ObjectFeatures]:
        """Features of the named objects (all by default): fitting costs per object, so ask for few."""
        wanted = [k for k in self._world.objects if names is None or k in set(names)]
        cloths = {i: k for i, k in self._world.flexes.items() if names is None or k in set(names)}
        if self.mode == "truth":
            truth = self._world.ground_truth()
            out = truth_features(truth.model_copy(update={"objects": {k: truth.objects[k] for k in wanted}}),
                                 self._shapes)
            return out | {k: truth_corner_features(k, self._world.flex_vertices(i), self._world.flex_side(i))
                          for i, k in cloths.items()}
        w = self._world
        views = [render_view(w.seg_depth_renderer, w.data, cam) for cam in CAMERAS]
        capped = [k for k in wanted if k in self._caps]  # one pass: a cap's pixels apart, then back in its object
        clouds = object_clouds(views, {k: self._geoms[k] - self._caps.get(k, set()) for k in wanted}
                               | {f"{k}:cap": self._caps[k] for k in capped})
        caps = {k: clouds.pop(f"{k}:cap") for k in capped}
        clouds |= {k: np.concatenate([clouds[k], caps[k]]) for k in capped}
        out = {k: closed_on_top(features(k, clouds[k], self._shapes[k].primitive(), views=views), clouds[k],
                                self._shapes[k]) for k in wanted}
        out |= {k: with_cap(out[k], cap.mean(axis=0)) for k, cap in caps.items() if len(cap) >= MIN_CAP_POINTS}
        if cloths:  # a cloth: its flex pixels (objtype FLEX), corners from the cloud's footprint
            flex_clouds = object_clouds(views, {k: {i} for i, k in cloths.items()}, objtype=int(mujoco.mjtObj.mjOBJ_FLEX),
                                        max_points=CLOUD_POINTS)
            for k, cloud in flex_clouds.items():
                out[k] = corner_features(k, cloud, cloud_corners(cloud, self._pixel_m) if len(cloud) >= 10 else {})
        return out


def truth_features(truth: GroundTruth, shapes: dict[str, Shape]) -> dict[str, ObjectFeatures]:
    """ObjectFeatures from the simulator's poses: what perfect perception would report."""
    out = {}
    for name, o in truth.objects.items():
        s = shapes[name]
        frame = _quat_matrix(np.array(o.quat))
        centre = np.array(o.pos)
        if s.kind == "cylinder":
            size = np.array([s.radius, s.half_height, 0.0])
            has_axis = True
        else:
            size = np.array(s.half_extents)
            a, b = np.sort(size)[::-1][:2]
            has_axis = a >= 1.3 * b
        fit = Fit(kind=s.kind, centre=centre, frame=frame, size=size, rms=0.0, inliers=1.0)
        axis = sign_normalized(fit.axis)
        h = fit.half_length
        tilt = math.degrees(math.acos(float(np.clip(axis[2], -1.0, 1.0))))
        spans = _spans(s)
        out[name] = ObjectFeatures(
            name=name, visible=True, n_points=0, fit="primitive", note="ground truth",
            centroid=_v(centre), raw_centroid=_v(centre), axis=_v(axis), extent=spans,
            tilt_deg=tilt if has_axis else None, upright=(tilt <= UPRIGHT_TOL_DEG) if has_axis else None,
            extremes={"top": _v(fit.support(UP)), "bottom": _v(fit.support(-UP)),
                      "axis_pos": _v(centre + h * axis), "axis_neg": _v(centre - h * axis)},
        )
        if s.cap:
            out[name] = with_cap(out[name], centre + (s.half_height - CAP_HALF_M) * frame[:, 2])
    return out


def closed_on_top(f: ObjectFeatures, cloud: np.ndarray, shape: Shape) -> ObjectFeatures:
    """A standing cup fitted with its opening up whose top is a closed disc of points (no cavity seen from above)
    stands on its rim: its opening is the lower end, and it is not upright. The points alone fit an upturned
    cup about as well either way up (the closed bottom is a few of them), so the fit's own choice is checked."""
    ex = f.extremes or {}
    if shape.kind != "cylinder" or shape.wall is None or not f.upright or f.centroid is None or "opening" not in ex:
        return f
    if ex["opening"][2] < f.centroid[2] - CAP_BELOW_M:  # fitted upturned: its opening faces down
        return f.model_copy(update={"upright": False})
    if ex["opening"][2] <= f.centroid[2] or len(cloud) == 0:
        return f
    p = np.asarray(cloud, float)
    c = np.asarray(f.centroid, float)
    top = p[p[:, 2] >= p[:, 2].max() - TOP_BAND_M]
    inner = np.hypot(top[:, 0] - c[0], top[:, 1] - c[1]) <= CLOSED_INNER_SHARE * (shape.radius - shape.wall)
    if int(inner.sum()) < MIN_CLOSED_POINTS:
        return f
    opening = 2 * c - np.asarray(ex["opening"], float)
    return f.model_copy(update={"extremes": {**ex, "opening": _v(opening)}, "upright": False,
                                "note": (f.note + "; " if f.note else "") + "closed on top: stands on its rim"})


TOP_BAND_M = 0.006
CLOSED_INNER_SHARE = 0.6
"""Points this share of the inner radius from the axis, in the top band: a closed end facing up."""
MIN_CLOSED_POINTS = 15


def with_cap(f: ObjectFeatures, cap: np.ndarray) -> ObjectFeatures:
    """The features with the seen cap (extreme `cap`, the centre of its pixels): an object whose cap hangs
    below its centre stands on its head, so it is not upright however vertical its axis."""
    below = f.centroid is not None and float(cap[2]) < f.centroid[2] - CAP_BELOW_M
    return f.model_copy(update={"extremes": {**f.extremes, "cap": _v(cap)},
                                "upright": False if below and f.upright else f.upright})


def _spans(s: Shape) -> tuple[float, float, float]:
    if s.kind == "cylinder":
        return (2 * s.half_height, 2 * s.radius, 2 * s.radius)
    he = sorted(s.half_extents, reverse=True)
    return (2 * he[0], 2 * he[1], 2 * he[2])


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _v(a: np.ndarray) -> tuple[float, float, float]:
    return (float(a[0]), float(a[1]), float(a[2]))
