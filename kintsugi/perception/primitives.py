"""Fit an object's known shape (cylinder, box, sphere) to a one-sided point cloud.

A camera sees only the near side of an object, so a raw centroid sits
centimetres towards the camera. The object catalogue knows the shape; the
surface points then fix the pose: minimise the signed distance of every point
to the primitive's surface (scipy least_squares, robust loss, a few starts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np
from pydantic import PositiveFloat, model_validator
from scipy.optimize import least_squares

from kintsugi.core.config import StrictModel
from kintsugi.perception.sdf import box_sdf, box_tray_sdf, cylinder_cup_sdf, cylinder_sdf, sphere_sdf

I3 = np.eye(3)
DEADZONE = float(np.sin(np.radians(5.0)))  # a direction within 5 deg of a face/axis counts as along it


class Primitive(StrictModel):
    """The known shape of an object, as a robot's object catalogue states it (metres, MuJoCo size conventions).

    cylinder: `radius`, optional `half_length` (half its height along the axis);
    box: `half_extents`; sphere: `radius`; none: no known shape (raw features only).
    `wall`: the object is a container open at one end (a cup: the cylinder's +axis end;
    a tray: the box's +z face) with walls and floor this thick, so that the points a
    camera sees inside it lie on the shape too.
    """

    kind: Literal["cylinder", "box", "sphere", "none"] = "none"
    radius: PositiveFloat | None = None
    half_length: PositiveFloat | None = None
    half_extents: tuple[PositiveFloat, PositiveFloat, PositiveFloat] | None = None
    wall: PositiveFloat | None = None

    @model_validator(mode="after")
    def _fields_match_kind(self) -> Primitive:
        need = {"cylinder": {"radius"}, "box": {"half_extents"}, "sphere": {"radius"}, "none": set()}[self.kind]
        allowed = need | ({"half_length", "wall"} if self.kind == "cylinder" else set())
        allowed |= {"wall"} if self.kind == "box" else set()
        given = {f for f in ("radius", "half_length", "half_extents", "wall") if getattr(self, f) is not None}
        if need - given:
            raise ValueError(f"a {self.kind} primitive needs {', '.join(sorted(need - given))}")
        if given - allowed:
            raise ValueError(f"a {self.kind} primitive takes no {', '.join(sorted(given - allowed))}")
        if self.wall is not None:
            if self.kind == "cylinder" and self.half_length is None:
                raise ValueError("a cylinder container (wall) needs half_length")
            inner = (self.radius, 2 * self.half_length) if self.kind == "cylinder" else (
                min(self.half_extents[:2]), 2 * self.half_extents[2])  # type: ignore[index]
            if self.wall >= min(inner):
                raise ValueError(f"wall {self.wall} leaves no cavity inside the {self.kind}")
        return self

    @classmethod
    def cylinder(cls, radius: float, half_length: float | None = None, wall: float | None = None) -> Primitive:
        return cls(kind="cylinder", radius=radius, half_length=half_length, wall=wall)

    @classmethod
    def box(cls, hx: float, hy: float, hz: float, wall: float | None = None) -> Primitive:
        return cls(kind="box", half_extents=(hx, hy, hz), wall=wall)

    @classmethod
    def sphere(cls, radius: float) -> Primitive:
        return cls(kind="sphere", radius=radius)


@dataclass(frozen=True)
class Fit:
    """A primitive placed in the world: centre, local frame (columns), residuals of the fit."""

    kind: Literal["cylinder", "box", "sphere"]
    centre: np.ndarray  # (3,)
    frame: np.ndarray  # (3, 3); cylinder axis = column 2
    size: np.ndarray  # cylinder (r, h, 0); box half extents; sphere (r, 0, 0)
    rms: float  # RMS of the inlier residuals, metres
    inliers: float  # fraction of points within the inlier tolerance of the surface
    wall: float = 0.0  # > 0: a container open at its local +z end

    @property
    def opening(self) -> np.ndarray | None:
        """Centre of a container's open end (None for solids)."""
        if self.wall <= 0.0 or self.kind == "sphere":
            return None
        return self.centre + self.frame[:, 2] * (self.size[1] if self.kind == "cylinder" else self.size[2])

    @property
    def axis(self) -> np.ndarray | None:
        """Cylinder axis, a box's longest axis, or None for a sphere (no axis)."""
        if self.kind == "cylinder":
            return self.frame[:, 2]
        if self.kind == "box":
            return self.frame[:, int(np.argmax(self.size))]
        return None

    @property
    def bound_radius(self) -> float:
        """Distance from the centre to the farthest point of the primitive."""
        if self.kind == "cylinder":
            return float(np.hypot(self.size[0], self.size[1]))
        return float(np.linalg.norm(self.size))

    @property
    def half_length(self) -> float:
        """Half the primitive's length along `axis`."""
        return float(self.size[1] if self.kind == "cylinder" else np.max(self.size))

    def support(self, direction: np.ndarray) -> np.ndarray:
        """Centre of the primitive's extreme face/edge/point in `direction` (e.g. +z: the top)."""
        d = self.frame.T @ (np.asarray(direction, float) / np.linalg.norm(direction))
        if self.kind == "sphere":
            local = self.size[0] * d
        elif self.kind == "box":
            local = np.where(np.abs(d) > DEADZONE, np.sign(d), 0.0) * self.size
        else:
            radial = np.hypot(d[0], d[1])
            local = np.zeros(3)
            if radial > DEADZONE:
                local[:2] = self.size[0] * d[:2] / radial
            if abs(d[2]) > DEADZONE:
                local[2] = np.sign(d[2]) * self.size[1]
        return self.centre + self.frame @ local


def _perp_basis(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def _frame_with_z(a: np.ndarray) -> np.ndarray:
    e1, e2 = _perp_basis(a)
    return np.column_stack([e1, e2, a])


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _exp(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of a rotation vector (Rodrigues)."""
    theta = math.sqrt(float(w @ w))
    if theta < 1e-12:
        return I3 + _skew(w)
    k = _skew(w / theta)
    return I3 + math.sin(theta) * k + (1.0 - math.cos(theta)) * (k @ k)


def _left_jacobian(w: np.ndarray) -> np.ndarray:
    """d exp(w) = exp(J_l(w) dw) exp(w): maps a rotation-vector change to a world-frame rotation."""
    theta = math.sqrt(float(w @ w))
    k = _skew(w)
    if theta < 1e-6:
        return I3 + 0.5 * k
    return I3 + (1 - math.cos(theta)) / theta**2 * k + (theta - math.sin(theta)) / theta**3 * (k @ k)


@dataclass(frozen=True)
class FitSettings:
    loss_scale: float = 0.002  # soft_l1 scale: residuals beyond this count less
    inlier_tol: float = 0.003  # a point this close to the surface is an inlier
    good_rms: float = 0.001  # stop trying further starts once a fit is this good
    max_nfev: int = 50


def _rigid_fit(
    p: np.ndarray,
    sdf: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    c0: np.ndarray,
    r0: np.ndarray,
    tc: np.ndarray,
    tr: np.ndarray,
    s: FitSettings,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Move a primitive (centre c0, frame r0) so that the points lie on its surface.

    Parameters x = [translation coords, rotation coords]: c = c0 + tc @ x_t,
    frame = exp(tr @ x_r) @ r0. Analytic Jacobian: moving the primitive by dc
    changes a point's distance by -g.dc, rotating it by phi about c by
    (g x (p - c)).phi, with g the surface gradient at the point.
    Robust: the residuals are soft-L1 scaled (as least_squares' loss="soft_l1")
    and solved with MINPACK's Levenberg-Marquardt, about 3x faster than "trf".
    """
    nt = tc.shape[1]
    f = s.loss_scale
    last: dict[bytes, tuple[np.ndarray, ...]] = {}

    def evaluate(x: np.ndarray) -> tuple[np.ndarray, ...]:
        key = x.tobytes()
        if key not in last:
            c, frame = c0 + tc @ x[:nt], _exp(tr @ x[nt:]) @ r0
            v = p - c
            d, g = sdf(v @ frame)
            z = np.sqrt(1.0 + (d / f) ** 2)
            root = np.sqrt(2.0 * f * f * (z - 1.0))  # sqrt of the soft-L1 cost of each residual
            last.clear()
            last[key] = (np.copysign(root, d), d, g @ frame.T, v, z, root)
        return last[key]

    def fun(x: np.ndarray) -> np.ndarray:
        return evaluate(x)[0]

    def jac(x: np.ndarray) -> np.ndarray:
        _, d, g, v, z, root = evaluate(x)
        g_x_v = np.column_stack(
            [g[:, 1] * v[:, 2] - g[:, 2] * v[:, 1], g[:, 2] * v[:, 0] - g[:, 0] * v[:, 2], g[:, 0] * v[:, 1] - g[:, 1] * v[:, 0]]
        )
        j = np.hstack([-g @ tc, g_x_v @ (_left_jacobian(tr @ x[nt:]) @ tr)])
        scale = np.where(root > 1e-12, np.abs(d) / (z * np.maximum(root, 1e-300)), 1.0)  # d root / d residual
        return j * scale[:, None]

    sol = least_squares(fun, np.zeros(nt + tr.shape[1]), jac=jac, method="lm", max_nfev=s.max_nfev, ftol=1e-6, xtol=1e-7)
    if sol.status < 0 or not np.all(np.isfinite(sol.x)):  # 0: evaluation budget spent, still a usable fit
        return None
    c, frame = c0 + tc @ sol.x[:nt], _exp(tr @ sol.x[nt:]) @ r0
    return c, frame, sdf((p - c) @ frame)[0]


def _quality(res: np.ndarray, s: FitSettings) -> tuple[float, float]:
    inl = np.abs(res) <= s.inlier_tol
    rms = float(np.sqrt(np.mean(res[inl] ** 2))) if inl.any() else float("inf")
    return rms, float(inl.mean())


def _good(f: Fit, s: FitSettings) -> bool:
    return f.rms <= s.good_rms and f.inliers >= 0.95


UP = np.array([0.0, 0.0, 1.0])
Contradiction = Callable[[Fit], "float | tuple[float, float]"]
"""How much other evidence contradicts a fit: one share, or (share that refuses it, share that ranks it)."""


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
        e1, e2 = _perp_basis(a)
        uv = (rim - centre) @ np.column_stack([e1, e2])
        lhs = np.column_stack([2 * uv, np.ones(len(uv))])
        sol, *_ = np.linalg.lstsq(lhs, (uv**2).sum(axis=1), rcond=None)
        fitted_r = math.sqrt(max(sol[2] + sol[0] ** 2 + sol[1] ** 2, 0.0))
        if abs(fitted_r - radius) < 0.25 * radius:  # a plausible rim circle, else keep the mean
            centre = centre + sol[0] * e1 + sol[1] * e2
    return centre - depth * a


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
        frame0 = _frame_with_z(a0 / np.linalg.norm(a0))
        across = frame0[:, :2]  # rotations about the axis change nothing
        c_start = p.mean(axis=0) if c0 is None else c0
        if wall is not None and half_length is not None:
            cup = lambda x: cylinder_cup_sdf(x, radius, half_length, wall)  # noqa: E731
            out = _rigid_fit(p, cup, c_start, frame0, I3, across, s)
        elif half_length is not None:
            out = _rigid_fit(p, lambda x: cylinder_sdf(x, radius, half_length), c_start, frame0, I3, across, s)
        else:  # infinitely long: the centre moves only across the axis, then sits mid-way along the points
            out = _rigid_fit(p, lambda x: cylinder_sdf(x, radius, None), c_start, frame0, across, across, s)
        if out is None:
            return None
        c, frame, res = out
        h = half_length
        if h is None:
            t = (p - c) @ frame[:, 2]
            c = c + frame[:, 2] * (t.max() + t.min()) / 2.0
            h = float(t.max() - t.min()) / 2.0
        return Fit("cylinder", c, frame, np.array([radius, h, 0.0]), *_quality(res, s), wall=wall or 0.0)

    return attempt


def _box_attempt(
    p: np.ndarray, he: np.ndarray, wall: float | None, r0: np.ndarray, s: FitSettings, c0: np.ndarray | None = None
):
    def sdf(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return box_sdf(x, he) if wall is None else box_tray_sdf(x, he, wall)

    def attempt() -> Fit | None:
        out = _rigid_fit(p, sdf, p.mean(axis=0) if c0 is None else c0, r0, I3, I3, s)
        return None if out is None else Fit("box", out[0], out[1], he, *_quality(out[2], s), wall=wall or 0.0)

    return attempt


def _sphere_attempt(p: np.ndarray, radius: float, s: FitSettings):
    def attempt() -> Fit | None:
        out = _rigid_fit(p, lambda x: sphere_sdf(x, radius), p.mean(axis=0), I3, I3, np.zeros((3, 0)), s)
        return None if out is None else Fit("sphere", out[0], I3, np.array([radius, 0.0, 0.0]), *_quality(out[2], s))

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


def surface_samples(fit: Fit, inset: float) -> np.ndarray:
    """A fixed set of points on the fitted primitive's surface, moved `inset` inwards (world frame)."""
    if fit.kind == "sphere":
        k = np.arange(120) + 0.5
        z = 1 - 2 * k / 120
        phi = np.pi * (1 + 5**0.5) * k
        rho = np.sqrt(1 - z * z)
        local = (fit.size[0] - inset) * np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    elif fit.kind == "cylinder":
        # A container's wall may be thinner than the inset: inside it, the camera rightly sees the cavity.
        r = max(fit.size[0] - (min(inset, fit.wall / 2) if fit.wall else inset), 0.0)
        h = max(fit.size[1] - inset, 0.0)
        zb = -fit.size[1] + (min(inset, fit.wall / 2) if fit.wall else inset)
        phi = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        side = [np.column_stack([r * np.cos(phi), r * np.sin(phi), np.full(24, t)]) for t in np.linspace(-h, h, 7)]
        ends = (zb,) if fit.wall else (-h, h)  # a container's open end is no surface
        caps = [np.column_stack([f * r * np.cos(phi), f * r * np.sin(phi), np.full(24, z)]) for f in (0.5, 1.0) for z in ends]
        local = np.vstack(side + caps + [[[0.0, 0.0, z] for z in ends]])
    else:
        he = np.maximum(fit.size - (min(inset, fit.wall / 2) if fit.wall else inset), 0.0)
        g = np.linspace(-1, 1, 5)
        u, v = (a.ravel() for a in np.meshgrid(g, g))
        faces = []
        for k in range(3):
            i, j = [m for m in range(3) if m != k]
            for sign in (-1.0, 1.0):
                if fit.wall and k == 2 and sign > 0:
                    continue  # a tray's open top
                face = np.zeros((25, 3))
                face[:, i], face[:, j], face[:, k] = u * he[i], v * he[j], sign * he[k]
                faces.append(face)
        local = np.vstack(faces)
    return fit.centre + local @ fit.frame.T


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
