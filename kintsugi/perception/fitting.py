"""Fit an object's known shape (cylinder, box, sphere) to a one-sided point cloud.

A camera sees only the near side of an object, so a raw centroid sits
centimetres towards the camera. The object catalogue knows the shape; the
surface points then fix the pose: minimise the signed distance of every point
to the primitive's surface (scipy least_squares, robust loss, a few starts).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from kintsugi.perception.primitives import Fit, Primitive
from kintsugi.perception.rigid_fit import I3, FitSettings, fit_quality, frame_with_z, perp_basis, rigid_fit
from kintsugi.perception.sdf import box_sdf, box_tray_sdf, cylinder_cup_sdf, cylinder_sdf, sphere_sdf

UP = np.array([0.0, 0.0, 1.0])
Contradiction = Callable[[Fit], "float | tuple[float, float]"]
"""How much other evidence contradicts a fit: one share, or (share that refuses it, share that ranks it)."""


def _good(f: Fit, s: FitSettings) -> bool:
    return f.rms <= s.good_rms and f.inliers >= 0.95


def _rim_start(p: np.ndarray, a: np.ndarray, depth: float, radius: float | None = None, band: float = 0.005) -> np.ndarray:
    """Initial centre `depth` behind the object's end towards a: the centre of the band of points at
    the extreme along a (a face, or a container's rim). Round: the centre of the circle through those
    points (an algebraic fit, right even for a partly seen rim); otherwise their mean. A face seen whole
    fixes the lateral position that surface points alone leave free (a plate's top), and a thin wall's
    parallel inner and outer faces could otherwise settle swapped."""
    t = p @ a
    rim = p[t >= t.max() - band]
    centre = rim.mean(axis=0)
    if radius is not None and len(rim) >= 10:
        e1, e2 = perp_basis(a)
        uv = (rim - centre) @ np.column_stack([e1, e2])
        lhs = np.column_stack([2 * uv, np.ones(len(uv))])
        sol, *_ = np.linalg.lstsq(lhs, (uv**2).sum(axis=1), rcond=None)
        fitted_r = math.sqrt(max(sol[2] + sol[0] ** 2 + sol[1] ** 2, 0.0))
        if abs(fitted_r - radius) < 0.25 * radius:  # a plausible rim circle, else keep the mean
            centre = centre + sol[0] * e1 + sol[1] * e2
    return centre - depth * a


def _level_axes(pca_axes: np.ndarray) -> list[np.ndarray]:
    """Horizontal starts for a cylinder lying on its side: the level part of the cloud's two main directions
    and the level direction across each (a cylinder about as long as it is wide has no telling main axis)."""
    out = []
    for k in (0, 1):
        a = np.array([pca_axes[0, k], pca_axes[1, k], 0.0])
        n = float(np.linalg.norm(a))
        if n > 1e-6:
            out += [a / n, np.array([-a[1], a[0], 0.0]) / n]
    return out


def _cylinder_attempt(
    p: np.ndarray,
    radius: float,
    half_length: float | None,
    wall: float | None,
    a0: np.ndarray,
    s: FitSettings,
    c0: np.ndarray | None = None,
):
    def attempt() -> Fit | None:
        frame0 = frame_with_z(a0 / np.linalg.norm(a0))
        across = frame0[:, :2]  # rotations about the axis change nothing
        c_start = p.mean(axis=0) if c0 is None else c0
        if wall is not None and half_length is not None:
            cup = lambda x: cylinder_cup_sdf(x, radius, half_length, wall)  # noqa: E731
            out = rigid_fit(p, cup, c_start, frame0, I3, across, s)
        elif half_length is not None:
            out = rigid_fit(p, lambda x: cylinder_sdf(x, radius, half_length), c_start, frame0, I3, across, s)
        else:  # infinitely long: the centre moves only across the axis, then sits mid-way along the points
            out = rigid_fit(p, lambda x: cylinder_sdf(x, radius, None), c_start, frame0, across, across, s)
        if out is None:
            return None
        c, frame, res = out
        h = half_length
        if h is None:
            t = (p - c) @ frame[:, 2]
            c = c + frame[:, 2] * (t.max() + t.min()) / 2.0
            h = float(t.max() - t.min()) / 2.0
        return Fit("cylinder", c, frame, np.array([radius, h, 0.0]), *fit_quality(res, s), wall=wall or 0.0)

    return attempt


def _box_attempt(
    p: np.ndarray, he: np.ndarray, wall: float | None, r0: np.ndarray, s: FitSettings, c0: np.ndarray | None = None
):
    def sdf(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return box_sdf(x, he) if wall is None else box_tray_sdf(x, he, wall)

    def attempt() -> Fit | None:
        out = rigid_fit(p, sdf, p.mean(axis=0) if c0 is None else c0, r0, I3, I3, s)
        return None if out is None else Fit("box", out[0], out[1], he, *fit_quality(out[2], s), wall=wall or 0.0)

    return attempt


def _sphere_attempt(p: np.ndarray, radius: float, s: FitSettings):
    def attempt() -> Fit | None:
        out = rigid_fit(p, lambda x: sphere_sdf(x, radius), p.mean(axis=0), I3, I3, np.zeros((3, 0)), s)
        return None if out is None else Fit("sphere", out[0], I3, np.array([radius, 0.0, 0.0]), *fit_quality(out[2], s))

    return attempt


def fit_primitive(
    p: np.ndarray,
    primitive: Primitive,
    pca_axes: np.ndarray,
    s: FitSettings,
    contradiction: Contradiction | None = None,
    max_contradiction: float = 0.05,
) -> tuple[Fit | None, int]:
    """Best fit of a known primitive over a few starts, and how many fits were refused.

    `contradiction(fit)` scores a fit against other evidence (the share of its surface
    the cameras saw through); above `max_contradiction` a fit is refused. Starts run in
    order of likelihood and stop at the first clean, uncontradicted fit; otherwise the
    best accepted one wins (most inliers, then least contradicted, then lowest RMS).
    A container's thin wall has parallel inner and outer faces, so the points alone
    also fit it about one wall thickness off (faces swapped); without a clean fit, the
    best one is retried one wall thickness away along each of its axes.
    """
    wall = primitive.wall
    if primitive.kind == "cylinder":
        squat = primitive.half_length is not None and primitive.half_length < primitive.radius
        likely = (pca_axes[:, 2], UP, pca_axes[:, 0]) if squat else (pca_axes[:, 0], UP, pca_axes[:, 1], pca_axes[:, 2])
        if wall is not None:  # a container most likely stands
            likely = (UP, *likely)
        likely = (*likely, *_level_axes(pca_axes))  # lying: a squat one's principal axes need not show its axis
        axes: list[np.ndarray] = []
        for a in likely:  # a squat cylinder (plate) is thinnest along its axis, a long one longest
            if all(abs(a @ b) < 0.95 for b in axes):
                axes.append(a)
        r, h = float(primitive.radius), primitive.half_length

        def cyl(a: np.ndarray, c0: np.ndarray | None = None):
            return _cylinder_attempt(p, r, h, wall, a, s, c0)

        if wall is None and h is None:
            attempts = [cyl(a) for a in axes]
        elif wall is None:  # centred below the upper end's face first (a face seen whole fixes the centre)
            ups = [a if a[2] >= 0 else -a for a in axes]
            attempts = [cyl(a, _rim_start(p, a, h, r)) for a in ups] + [cyl(a) for a in axes]
        else:  # a container's two ends differ: each axis both ways, centred on its rim
            attempts = [cyl(e, _rim_start(p, e, h, r)) for a in axes for e in (a, -a)]  # type: ignore[arg-type]

        def hop(f: Fit, c: np.ndarray):
            return cyl(f.frame[:, 2], c)

    elif primitive.kind == "box":
        he = np.asarray(primitive.half_extents, float)
        frames = box_starts(pca_axes, p, he)
        if wall is None:  # centred below the top face first (seen whole from above, it fixes the centre)
            attempts = []
            for r0 in frames:
                k = int(np.argmax(np.abs(r0[2])))
                up = r0[:, k] * np.sign(r0[2, k])
                attempts.append(_box_attempt(p, he, None, r0, s, _rim_start(p, up, he[k])))
            attempts += [_box_attempt(p, he, None, r0, s) for r0 in frames]
        else:  # open side up first, then upside down
            frames = [f for r0 in frames for f in (r0, r0 * [1.0, -1.0, -1.0])]
            attempts = [_box_attempt(p, he, wall, r0, s, _rim_start(p, r0[:, 2], he[2])) for r0 in frames]

        def hop(f: Fit, c: np.ndarray):
            return _box_attempt(p, he, wall, f.frame, s, c)

    elif primitive.kind == "sphere":
        attempts = [_sphere_attempt(p, float(primitive.radius), s)]
    else:
        return None, 0

    accepted: list[tuple[Fit, float]] = []
    tried: list[tuple[Fit, float]] = []

    def rank(fc: tuple[Fit, float]) -> tuple[float, float, float]:
        return (round(fc[0].inliers, 1), -round(fc[1], 2), -fc[0].rms)

    def run(batch) -> bool:
        for attempt in batch:
            fit = attempt()
            if fit is None:
                continue
            c = contradiction(fit) if contradiction is not None else 0.0
            refuse, c = c if isinstance(c, tuple) else (c, c)
            tried.append((fit, c))
            if refuse <= max_contradiction:
                accepted.append((fit, c))
                if _good(fit, s) and c <= max_contradiction / 2:
                    return True
        return False

    if not run(attempts) and wall is not None and tried:
        f = max(tried, key=rank)[0]
        run([hop(f, f.centre + sign * wall * f.frame[:, k]) for k in range(3) for sign in (1.0, -1.0)])
    best = max(accepted, key=rank, default=None)
    return (best[0] if best else None), len(tried) - len(accepted)


def box_starts(pca_axes: np.ndarray, p: np.ndarray, half_extents: np.ndarray) -> list[np.ndarray]:
    """Initial frames: the box resting on its thinnest side (the likeliest pose on a table), the
    cloud's principal axes on the box's sorted extents, then the box resting on its other sides;
    resting boxes have their long side along the cloud's horizontal principal direction."""
    order = np.argsort(-np.asarray(half_extents))
    r_pca = np.zeros((3, 3))
    r_pca[:, order] = pca_axes
    if np.linalg.det(r_pca) < 0:
        r_pca[:, order[2]] *= -1
    xy = p[:, :2] - p[:, :2].mean(axis=0)
    w, v = np.linalg.eigh(xy.T @ xy)
    long_dir = np.r_[v[:, 1], 0.0]
    short_dir = np.cross([0.0, 0.0, 1.0], long_dir)
    starts = []
    for up in np.argsort(half_extents):
        others = [j for j in range(3) if j != up]
        longer, shorter = sorted(others, key=lambda j: -half_extents[j])
        r = np.zeros((3, 3))
        r[:, up] = [0.0, 0.0, 1.0]
        r[:, longer] = long_dir
        r[:, shorter] = short_dir
        if np.linalg.det(r) < 0:
            r[:, shorter] *= -1
        starts.append(r)
    return [starts[0], r_pca, *starts[1:]]
