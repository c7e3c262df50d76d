"""Object features a method may see: centroid, principal axis, extremal points, uprightness.

Task-free and perceived only: a cloud fused from segmentation + depth renders
(`object_cloud`), plus the object's known shape from the catalogue
(`Primitive`, possibly a container). Everything is in metres, in the world frame.
When the shape fixes the pose, the features come from the fitted primitive
(`fit="primitive"`); otherwise, or when that fit fails or contradicts what the
cameras saw, from the raw cloud (`fit="raw"`, with a note saying why).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import cv2
import numpy as np
from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError
from kintsugi.perception.cloud import CameraModel, View, body_geom_ids, object_cloud, object_clouds
from kintsugi.perception.render import SegDepthRenderer, render_view
from kintsugi.perception.fitting import fit_primitive
from kintsugi.perception.primitives import Fit, Primitive, surface_samples
from kintsugi.perception.rigid_fit import FitSettings

__all__ = [
    "CameraModel",
    "FeatureConfig",
    "ObjectFeatures",
    "Primitive",
    "SegDepthRenderer",
    "View",
    "body_geom_ids",
    "features",
    "object_cloud",
    "object_clouds",
    "render_view",
    "see_through",
    "see_through_shares",
    "sign_normalized",
]

Vec3 = tuple[float, float, float]
UP = np.array([0.0, 0.0, 1.0])
LEVEL = float(np.sin(np.radians(2.0)))  # axes closer than this to horizontal are signed by x, not z


class FeatureConfig(StrictModel):
    """Thresholds of the feature extractor."""

    min_points: int = Field(10, ge=3)  # fewer points: the object counts as not visible
    min_fit_points: int = Field(30, ge=3)  # fewer points: no primitive fit, raw features
    fit_points: int = Field(400, ge=10)  # the fit uses at most this many (evenly spaced) points
    min_inliers: float = Field(0.7, gt=0.0, le=1.0)  # a fit must put this share of points on its surface
    inlier_tol: float = Field(0.003, gt=0.0)  # metres from the surface that count as on it
    max_shift: float = Field(0.02, gt=0.0)  # a fit may move the centre this much beyond the primitive's half size
    max_see_through: float = Field(0.05, ge=0.0, le=1.0)  # share of a fitted surface the cameras may see through
    see_through_tol: float = Field(0.005, gt=0.0)  # metres beyond the fitted surface that count as seeing through
    band: float = Field(0.005, gt=0.0)  # raw extremes: centre of the points within this of the extreme
    upright_tol_deg: float = Field(15.0, gt=0.0, lt=90.0)  # upright: axis within this of vertical
    min_elongation: float = Field(1.3, ge=1.0)  # raw/box axis is defined when spread ratio >= this


class ObjectFeatures(StrictModel):
    """What a method may know about one object, from its perceived cloud (metres, world frame).

    `axis` is the principal axis (a fitted cylinder's axis, a box's longest side), unit,
    pointing up; within 2 deg of horizontal it points to +x (then +y) instead.
    `extremes`: `top` / `bottom` (centre of the highest / lowest face, edge or point) and
    `axis_pos` / `axis_neg` (the two ends along `axis`), and for a fitted container
    `opening` (the centre of its open end). Fields other than name, visible,
    n_points, fit and note are None when the object is not visible.
    """

    name: str
    visible: bool
    n_points: int
    fit: Literal["primitive", "raw"]
    fit_rms: float | None = None  # RMS distance of inlier points to the fitted surface
    fit_inliers: float | None = None  # share of points on the fitted surface
    note: str = ""  # why the features are raw, or why not visible
    centroid: Vec3 | None = None
    raw_centroid: Vec3 | None = None  # mean of the visible points (biased towards the cameras)
    axis: Vec3 | None = None
    extent: Vec3 | None = None  # cloud size along the axis, then along its two principal directions across it
    tilt_deg: float | None = None  # angle between axis and vertical, 0..90
    upright: bool | None = None  # None when the object has no well-defined axis
    extremes: dict[str, Vec3] = Field(default_factory=dict)

    def along(self, fraction: float) -> Vec3:
        """The point a fraction of the way from `axis_neg` (0) to `axis_pos` (1), e.g. 0.75 up a bottle."""
        if not self.visible:
            raise ConfigError(f"object {self.name!r} is not visible: it has no points along its axis")
        a, b = np.array(self.extremes["axis_neg"]), np.array(self.extremes["axis_pos"])
        return _vec(a + fraction * (b - a))


def _vec(v: np.ndarray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


def sign_normalized(a: np.ndarray) -> np.ndarray:
    """Unit axis pointing up; within 2 deg of horizontal, pointing to +x (then +y)."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    for k, tol in ((2, LEVEL), (0, LEVEL), (1, 0.0)):
        if abs(a[k]) > tol:
            return a if a[k] > 0 else -a
    return a


def _principal(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal directions (columns, by decreasing spread) and their variances."""
    q = p - p.mean(axis=0)
    w, v = np.linalg.eigh(q.T @ q / len(p))
    return v[:, ::-1], np.maximum(w[::-1], 0.0)


def _band_extreme(p: np.ndarray, d: np.ndarray, band: float) -> np.ndarray:
    """Centre of the points within `band` of the extreme along d, moved onto the extreme plane."""
    t = p @ d
    mean = p[t >= t.max() - band].mean(axis=0)
    return mean + (t.max() - mean @ d) * d


def see_through(fit: Fit, views: Sequence[tuple[CameraModel, np.ndarray, np.ndarray]], cfg: FeatureConfig) -> float:
    """Share of the fitted solid's surface that some camera sees through (it saw something farther away).

    A shape can match the visible points and still claim space the cameras saw
    empty (a too-big cylinder on a box, a bottle fitted upside down on its cap).
    """
    return see_through_shares(fit, views, cfg)[1]


def nearest_depths(views: Sequence[tuple[CameraModel, np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    """Each view's depth as the minimum over every pixel's 3x3 neighbourhood (once per view, not per fit)."""
    return [cv2.erode(np.asarray(d, dtype=np.float32), np.ones((3, 3), np.uint8)) for _, d, _ in views]


def see_through_shares(fit: Fit, views: Sequence[tuple[CameraModel, np.ndarray, np.ndarray]], cfg: FeatureConfig,
                       nearest: Sequence[np.ndarray] | None = None) -> tuple[float, float]:
    """(share seen through in its pixel and all eight around it, share seen through in its own pixel).

    The first decides whether a fit is refused: a cup's 5 mm rim is a pixel or two
    wide from above, so a sample inside the wall often lands in the next pixel,
    which looks into the cavity (5.5 % of a perfect fit's surface on one pour-dual
    seed, where wrong fits score 12 % or more). The second ranks the fits that
    pass: a container fitted one wall thickness off is told apart only pixel by pixel.
    """
    pts = surface_samples(fit, cfg.inlier_tol)
    seen = bad_near = bad = 0
    nearest = nearest_depths(views) if nearest is None else nearest
    for (cam, depth, _), near in zip(views, nearest):
        z = -((pts - cam.pos) @ cam.xmat[:, 2])
        pix = np.floor(cam.project(pts)).astype(np.int64)
        ok = (z > 1e-6) & (pix[:, 0] >= 0) & (pix[:, 0] < cam.width) & (pix[:, 1] >= 0) & (pix[:, 1] < cam.height)
        limit = z[ok] + cfg.see_through_tol
        seen += int(ok.sum())
        bad += int(np.count_nonzero(np.asarray(depth)[pix[ok, 1], pix[ok, 0]] > limit))
        bad_near += int(np.count_nonzero(near[pix[ok, 1], pix[ok, 0]] > limit))
    return (bad_near / seen, bad / seen) if seen else (0.0, 0.0)


def _box_axis_defined(size: np.ndarray, min_elongation: float) -> bool:
    a, b = np.sort(size)[::-1][:2]
    return a >= min_elongation * b


def features(
    name: str,
    cloud: np.ndarray,
    primitive: Primitive | None = None,
    config: FeatureConfig | None = None,
    views: Sequence[tuple[CameraModel, np.ndarray, np.ndarray]] | None = None,
) -> ObjectFeatures:
    """Features of one object's fused cloud; fits `primitive` when it is known.

    Pass the `views` the cloud came from to reject fits that claim space the
    cameras saw through (recommended: it also settles which way a cylinder
    seen only from one end extends).
    """
    cfg = config or FeatureConfig()
    p = np.asarray(cloud, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ConfigError(f"cloud of {name!r} must have shape (N, 3), got {p.shape}")
    p = p[np.isfinite(p).all(axis=1)]
    n = len(p)
    if n < cfg.min_points:
        return ObjectFeatures(name=name, visible=False, n_points=n, fit="raw", note=f"{n} points < {cfg.min_points}")

    raw_centroid = p.mean(axis=0)
    axes, var = _principal(p)
    raw_axis = sign_normalized(axes[:, 0])
    elongated = var[0] >= cfg.min_elongation**2 * var[1]

    fit: Fit | None = None
    note = ""
    kind = primitive.kind if primitive is not None else "none"
    if kind == "none":
        note = "no known shape"
    elif n < cfg.min_fit_points:
        note = f"{n} points < {cfg.min_fit_points} for a {kind} fit"
    else:
        s = FitSettings(inlier_tol=cfg.inlier_tol)
        q = p[np.linspace(0, n - 1, cfg.fit_points).round().astype(np.int64)] if n > cfg.fit_points else p
        near = nearest_depths(views) if views else None
        seen = (lambda f: see_through_shares(f, views, cfg, near)) if views else None
        fit, rejected = fit_primitive(q, primitive, axes, s, seen, cfg.max_see_through)  # type: ignore[arg-type]
        if fit is None:
            note = f"{kind} fit contradicts the views" if rejected else f"{kind} fit did not converge"
        elif fit.inliers < cfg.min_inliers:
            note = f"{kind} fit put only {fit.inliers:.0%} of points on its surface"
            fit = None
        elif (shift := float(np.linalg.norm(fit.centre - raw_centroid))) > fit.bound_radius + cfg.max_shift:
            note = f"{kind} fit moved the centre {shift * 1000:.0f} mm from the points"
            fit = None

    if fit is not None:
        centroid = fit.centre
        fit_axis = fit.axis
        if fit_axis is None:  # sphere
            axis, has_axis = UP, False
        else:
            axis = sign_normalized(fit_axis)
            has_axis = fit.kind == "cylinder" or _box_axis_defined(fit.size, cfg.min_elongation)
        h = fit.half_length
        extremes = {
            "top": fit.support(UP),
            "bottom": fit.support(-UP),
            "axis_pos": centroid + h * axis if fit_axis is not None else fit.support(axis),
            "axis_neg": centroid - h * axis if fit_axis is not None else fit.support(-axis),
        }
        if (opening := fit.opening) is not None:
            extremes["opening"] = opening
    else:
        centroid, axis, has_axis = raw_centroid, raw_axis, bool(elongated)
        extremes = {
            "top": _band_extreme(p, UP, cfg.band),
            "bottom": _band_extreme(p, -UP, cfg.band),
            "axis_pos": _band_extreme(p, axis, cfg.band),
            "axis_neg": _band_extreme(p, -axis, cfg.band),
        }

    across = p - np.outer(p @ axis, axis)
    others = _principal(across)[0][:, :2]  # the cloud's main directions across the axis
    spans = [float(np.ptp(p @ d)) for d in (axis, others[:, 0], others[:, 1])]
    tilt = float(np.degrees(np.arccos(min(abs(float(axis[2])), 1.0))))
    return ObjectFeatures(
        name=name,
        visible=True,
        n_points=n,
        fit="primitive" if fit is not None else "raw",
        fit_rms=fit.rms if fit is not None else None,
        fit_inliers=fit.inliers if fit is not None else None,
        note=note,
        centroid=_vec(centroid),
        raw_centroid=_vec(raw_centroid),
        axis=_vec(axis),
        extent=(spans[0], spans[1], spans[2]),
        tilt_deg=tilt if has_axis else None,
        upright=(tilt <= cfg.upright_tol_deg) if has_axis else None,
        extremes={k: _vec(v) for k, v in extremes.items()},
    )
