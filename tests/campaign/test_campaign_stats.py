"""Wilson intervals against published/known values and scipy's own implementation."""

import math

import pytest
from scipy.stats import binomtest

from kintsugi.campaign.stats import fmt, format_rate, mean, median, ratio, wilson_interval


@pytest.mark.parametrize(
    ("k", "n", "low", "high"),
    [
        (0, 30, 0.0, 0.11351),
        (15, 30, 0.33154, 0.66846),
        (30, 30, 0.88649, 1.0),
        (25, 30, 0.66436, 0.92663),
        (1, 10, 0.01787, 0.40415),
    ],
)
def test_wilson_golden(k, n, low, high):
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(low, abs=1e-5)
    assert hi == pytest.approx(high, abs=1e-5)


@pytest.mark.parametrize("n", [1, 7, 30, 101])
def test_wilson_matches_scipy(n):
    for k in range(n + 1):
        ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
        lo, hi = wilson_interval(k, n)
        assert lo == pytest.approx(ci.low, abs=1e-9)
        assert hi == pytest.approx(ci.high, abs=1e-9)


def test_wilson_edges():
    assert wilson_interval(0, 0) == (0.0, 1.0)
    with pytest.raises(ValueError):
        wilson_interval(3, 2)
    lo99, hi99 = wilson_interval(15, 30, confidence=0.99)
    lo95, hi95 = wilson_interval(15, 30)
    assert lo99 < lo95 and hi99 > hi95


def test_format_rate():
    assert format_rate(25, 30) == "83 [66–93]"
    assert format_rate(0, 30) == "0 [0–11]"
    assert format_rate(30, 30) == "100 [89–100]"
    assert format_rate(0, 0) == "—"


def test_means():
    assert mean([1, 2, 3]) == 2.0
    assert math.isnan(mean([]))
    assert median([3, 1, 2, 10]) == 2.5
    assert math.isnan(ratio(1.0, 0))
    assert fmt(math.nan) == "—" and fmt(0.25, 2) == "0.25"
