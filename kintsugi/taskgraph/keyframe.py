"""Node synthesis (Eq. 9): a keyframe position that satisfies a sub-goal's constraints, by a coarse global
search (scipy `dual_annealing`) refined by `SLSQP` with the constraints as inequalities.

Task-free: the caller supplies `predict(x) -> Features` (what the features would be with the end effector
at x, e.g. a held object carried rigidly) and extra soft terms (reachability, collision). The objective is
those terms plus a regularizer towards a reference (the composer's intended target) and, when re-solving,
towards the last solution (consistency, against perception jitter).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from scipy.optimize import dual_annealing, minimize

from kintsugi.taskgraph.features import Features

Penalty = Callable[[np.ndarray], float]
VIOLATION_WEIGHT = 1e3
"""Hinge weight of a violated constraint in the global search (metres and degrees alike)."""


@dataclass(frozen=True)
class Keyframe:
    x: np.ndarray
    ok: bool
    """Every constraint holds within `tol` and every soft term is (near) zero."""
    violation: float
    """Largest constraint value at x (<= tol when ok); NaN if a constraint could not be evaluated."""
    penalty: float
    message: str
    evaluations: int


def solve_keyframe(constraints: Sequence, predict: Callable[[np.ndarray], Features], reference: np.ndarray,
                   bounds: Sequence[tuple[float, float]], penalties: Sequence[Penalty] = (),
                   last: np.ndarray | None = None, reg_weight: float = 1.0, consistency_weight: float = 0.5,
                   tol: float = 1e-3, maxiter: int = 40, seed: int = 0) -> Keyframe:
    """Minimise penalties + reg |x - reference|^2 (+ consistency |x - last|^2) s.t. c_i(predict(x)) <= 0."""
    reference = np.asarray(reference, float)
    lo = np.array([b[0] for b in bounds])
    hi = np.array([b[1] for b in bounds])
    count = [0]

    def values(x: np.ndarray) -> np.ndarray:
        count[0] += 1
        f = predict(x)
        return np.array([c.evaluate(f) for c in constraints], float)

    def soft(x: np.ndarray) -> float:
        total = reg_weight * float(np.sum((x - reference) ** 2)) + sum(p(x) for p in penalties)
        if last is not None:
            total += consistency_weight * float(np.sum((x - last) ** 2))
        return total

    def merit(x: np.ndarray) -> float:
        v = np.nan_to_num(values(x), nan=1.0)
        return soft(x) + VIOLATION_WEIGHT * float(np.sum(np.maximum(v, 0.0)))

    start = np.clip(last if last is not None else reference, lo, hi)
    coarse = dual_annealing(merit, bounds=list(zip(lo, hi)), x0=start, maxiter=maxiter, seed=seed,
                            no_local_search=True)
    x0 = coarse.x if coarse.fun <= merit(start) else start
    cons = [{"type": "ineq", "fun": (lambda x, i=i: -np.nan_to_num(values(x)[i], nan=1.0))}
            for i in range(len(constraints))]
    fine = minimize(soft, x0, method="SLSQP", bounds=list(zip(lo, hi)), constraints=cons,
                    options={"maxiter": 100, "ftol": 1e-9})
    x = np.clip(fine.x if np.all(np.isfinite(fine.x)) else x0, lo, hi)
    v = values(x)
    worst = float(np.max(v)) if len(v) else -math.inf
    pen = float(sum(p(x) for p in penalties))
    ok = bool(np.all(np.isfinite(v)) and worst <= tol and pen <= tol)
    if ok:
        msg = f"solved: worst constraint {worst:.4g}, {count[0]} evaluations"
    else:
        bad = [f"{constraints[i].kind} {v[i]:.3g}" for i in range(len(v)) if not v[i] <= tol]
        msg = (f"no feasible keyframe ({fine.message}): " + (", ".join(bad) or "constraints hold") +
               (f"; soft penalty {pen:.3g}" if pen > tol else ""))
    return Keyframe(x=x, ok=ok, violation=worst, penalty=pen, message=msg, evaluations=count[0])
