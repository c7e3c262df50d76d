"""Signed distances (and their gradients) of points to primitives, in the primitive's own frame.

Each function returns (d, g): d < 0 inside, g the unit gradient (outward normal of the
nearest surface), which the pose fit turns into an analytic Jacobian.
"""

from __future__ import annotations

import numpy as np


def cylinder_sdf(x: np.ndarray, r: float, h: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Closed cylinder along local z (h = None: infinitely long)."""
    rho = np.hypot(x[:, 0], x[:, 1])
    safe = np.where(rho > 1e-12, rho, 1.0)
    n = np.column_stack([np.where(rho > 1e-12, x[:, 0] / safe, 1.0), x[:, 1] / safe, np.zeros(len(x))])
    dr = rho - r
    if h is None:
        return dr, n
    s = np.where(x[:, 2] >= 0.0, 1.0, -1.0)
    da = np.abs(x[:, 2]) - h
    cap = np.column_stack([np.zeros(len(x)), np.zeros(len(x)), s])
    corner = (dr > 0.0) & (da > 0.0)
    d = np.where(corner, np.hypot(dr, da), np.maximum(dr, da))
    g = np.where((dr >= da)[:, None], n, cap)
    if corner.any():
        g[corner] = (dr[corner, None] * n[corner] + da[corner, None] * cap[corner]) / d[corner, None]
    return d, g


def box_sdf(x: np.ndarray, he: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Box centred at the origin with half extents he."""
    s = np.where(x >= 0.0, 1.0, -1.0)
    q = np.abs(x) - he
    out = np.maximum(q, 0.0)
    dist_out = np.sqrt((out * out).sum(axis=1))
    outside = dist_out > 0.0
    nearest_face = np.arange(3) == q.argmax(axis=1)[:, None]  # inside: the gradient points out of the nearest face
    d = np.where(outside, dist_out, q.max(axis=1))
    g = s * np.where(outside[:, None], out / np.where(outside, dist_out, 1.0)[:, None], nearest_face)
    return d, g


def container_sdf(
    outer: tuple[np.ndarray, np.ndarray], cavity: tuple[np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """The solid minus its cavity (a CSG difference): max(outer, -cavity)."""
    (a, ga), (b, gb) = outer, cavity
    use_outer = a >= -b
    return np.where(use_outer, a, -b), np.where(use_outer[:, None], ga, -gb)


def cylinder_cup_sdf(x: np.ndarray, r: float, h: float, wall: float) -> tuple[np.ndarray, np.ndarray]:
    """A cup: cylinder open at +z, walls and floor `wall` thick (the cavity runs out past the rim)."""
    return container_sdf(cylinder_sdf(x, r, h), cylinder_sdf(x - [0.0, 0.0, wall], r - wall, h))


def box_tray_sdf(x: np.ndarray, he: np.ndarray, wall: float) -> tuple[np.ndarray, np.ndarray]:
    """A tray: box open at +z, walls and floor `wall` thick."""
    return container_sdf(box_sdf(x, he), box_sdf(x - [0.0, 0.0, wall], he - [wall, wall, 0.0]))


def sphere_sdf(x: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray]:
    norm = np.linalg.norm(x, axis=1)
    return norm - r, x / np.where(norm > 1e-12, norm, 1.0)[:, None]
