"""MPPI weights with the temperature chosen for a target effective sample size (CoRAL S1-B).

A fixed temperature is tied to the scale of the cost, which a generated cost does not fix;
choosing it each iteration so that ESS = (sum w)^2 / sum w^2 hits a fraction of the samples
makes the update equally sharp whatever the cost's units.
"""

from __future__ import annotations

import numpy as np

from kintsugi.core.errors import ConfigError

_BISECT_STEPS = 60


def _weights(shifted: np.ndarray, lam: float) -> np.ndarray:
    """exp(-shifted / lam) with infinite costs at exactly zero weight."""
    with np.errstate(over="ignore", invalid="ignore"):
        w = np.exp(-shifted / lam)
    w[~np.isfinite(shifted)] = 0.0
    return w


def _ess(w: np.ndarray) -> float:
    s = w.sum()
    return float(s * s / np.dot(w, w)) if s > 0 else 0.0


def temperature_for_ess(costs: np.ndarray, ess_fraction: float) -> tuple[float, float]:
    """Temperature lam whose weights have ESS = ess_fraction x (number of finite costs).

    Bisection on log(lam): ESS grows monotonically from 1 (lam -> 0, all weight on the best)
    to the number of finite samples (lam -> inf, uniform). Costs are shifted by the best one
    first (S5). Infinite or NaN costs (invalid rollouts) get zero weight and are not counted
    in the target, so they can neither win nor dilute the update.

    Returns (lam, ess) with ess the effective sample size (a count) at lam. All-equal finite
    costs give ess = n for any lam (returns lam = 1). No finite cost returns (inf, 0).
    """
    if not 0.0 < ess_fraction <= 1.0:
        raise ConfigError(f"ess_fraction must be in (0, 1], got {ess_fraction}")
    c = np.asarray(costs, dtype=float).ravel()
    finite = np.isfinite(c)
    n = int(finite.sum())
    if n == 0:
        return float("inf"), 0.0
    shifted = np.where(finite, c - c[finite].min(), np.inf)
    spread = float(shifted[finite].max())
    if spread <= 0.0:
        return 1.0, float(n)
    target = max(1.0, ess_fraction * n)
    # ESS(lo) ~ 1 and ESS(hi) ~ n bracket any target in [1, n]
    positive = shifted[finite & (shifted > 0)]
    log_lo = np.log(positive.min()) - np.log(1e3)
    log_hi = np.log(spread) + np.log(1e6)
    for _ in range(_BISECT_STEPS):
        mid = 0.5 * (log_lo + log_hi)
        if _ess(_weights(shifted, float(np.exp(mid)))) < target:
            log_lo = mid
        else:
            log_hi = mid
    lam = float(np.exp(0.5 * (log_lo + log_hi)))
    return lam, _ess(_weights(shifted, lam))


def mppi_weights(costs: np.ndarray, lam: float) -> np.ndarray:
    """Normalised exponential weights; invalid (inf/NaN) costs get zero weight."""
    c = np.asarray(costs, dtype=float).ravel()
    finite = np.isfinite(c)
    w = np.zeros_like(c)
    if not finite.any():
        return w
    shifted = np.where(finite, c - c[finite].min(), np.inf)
    w = _weights(shifted, lam if np.isfinite(lam) else 1.0)
    return w / w.sum()
