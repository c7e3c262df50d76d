"""Move a known surface so that measured points lie on it: a robust rigid least-squares fit.

The pose is parameterised by translation and rotation-vector coordinates about a start pose; the Jacobian
is analytic (through the surface gradient of the signed distance), and the residuals are soft-L1 scaled and
solved with MINPACK's Levenberg-Marquardt (scipy least_squares).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.optimize import least_squares

I3 = np.eye(3)


def perp_basis(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def frame_with_z(a: np.ndarray) -> np.ndarray:
    e1, e2 = perp_basis(a)
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


def rigid_fit(
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


def fit_quality(res: np.ndarray, s: FitSettings) -> tuple[float, float]:
    inl = np.abs(res) <= s.inlier_tol
    rms = float(np.sqrt(np.mean(res[inl] ** 2))) if inl.any() else float("inf")
    return rms, float(inl.mean())
