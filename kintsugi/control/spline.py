"""Control splines: knot values over a horizon, evaluated at any times.

Every interpolation kind used here is linear in the knot values, so evaluating K sampled
knot sets on the rollout grid is one matrix product with a basis computed once. Queries
outside the knot span hold the end values (a shifted plan keeps its last command).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from scipy.interpolate import CubicSpline

Interp = Literal["zero", "linear", "cubic"]


def basis(kind: Interp, knot_t: np.ndarray, query_t: np.ndarray) -> np.ndarray:
    """(len(query_t), len(knot_t)) matrix B with values(query) = B @ knot_values."""
    knot_t = np.asarray(knot_t, dtype=float)
    q = np.clip(np.asarray(query_t, dtype=float), knot_t[0], knot_t[-1])
    n = len(knot_t)
    if n == 1:
        return np.ones((len(q), 1))
    if kind == "zero":
        idx = np.clip(np.searchsorted(knot_t, q, side="right") - 1, 0, n - 1)
        return np.eye(n)[idx]
    if kind == "linear":
        return np.stack([np.interp(q, knot_t, col) for col in np.eye(n)], axis=1)
    if kind == "cubic":
        # not-a-knot needs 4 knots; with fewer, a natural spline (2 knots: a line)
        bc = "not-a-knot" if n >= 4 else "natural"
        return CubicSpline(knot_t, np.eye(n), axis=0, bc_type=bc)(q)
    raise ValueError(f"unknown interpolation {kind!r}; use zero, linear or cubic")


def evaluate(kind: Interp, knot_t: np.ndarray, values: np.ndarray, query_t: np.ndarray) -> np.ndarray:
    """Values of one spline (knots, nu) at query times -> (len(query_t), nu)."""
    return basis(kind, knot_t, query_t) @ values
