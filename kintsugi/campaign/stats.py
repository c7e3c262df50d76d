"""Small statistics for campaign tables: Wilson score intervals and tolerant means.

Success rates from 30 trials per cell are coarse; the Wilson interval is the
honest way to show how coarse (it stays inside [0, 1] and is sensible at 0/n
and n/n, where the normal approximation collapses to a zero-width interval).
"""

from __future__ import annotations

import math
import statistics
from typing import Iterable

from scipy.stats import binomtest


def wilson_interval(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for k successes out of n trials, as fractions in [0, 1] (scipy's `binomtest`).

    With n == 0 there is no information, so the interval is the whole range (0, 1).
    """
    if n < 0 or k < 0 or k > n:
        raise ValueError(f"need 0 <= k <= n, got k={k}, n={n}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    if n == 0:
        return 0.0, 1.0
    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def format_rate(k: int, n: int, confidence: float = 0.95) -> str:
    """`83 [66–93]`: success percentage with its Wilson interval, all rounded to integers."""
    if n == 0:
        return "—"
    low, high = wilson_interval(k, n, confidence)
    return f"{round(100 * k / n)} [{round(100 * low)}–{round(100 * high)}]"


def mean(values: Iterable[float]) -> float:
    """Arithmetic mean; NaN (not an exception) for no values, so an empty cell renders as '—'."""
    vals = [float(v) for v in values]
    return sum(vals) / len(vals) if vals else math.nan


def median(values: Iterable[float]) -> float:
    """Median; NaN for no values."""
    vals = [float(v) for v in values]
    return statistics.median(vals) if vals else math.nan


def ratio(numerator: float, denominator: float) -> float:
    """numerator / denominator, NaN when the denominator is zero (e.g. latency per call with no calls)."""
    return numerator / denominator if denominator else math.nan


def fmt(value: float, digits: int = 1) -> str:
    """Fixed-point number, '—' for NaN."""
    return "—" if math.isnan(value) else f"{value:.{digits}f}"
