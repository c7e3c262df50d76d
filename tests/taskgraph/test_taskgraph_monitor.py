"""Eq. 12 persistence: fire on exactly the W-th consecutive step above the margin; reset otherwise."""

from __future__ import annotations

import math

import pytest

from kintsugi.taskgraph.features import ArmState, Features, ObjectState
from kintsugi.taskgraph.model import Monitor
from kintsugi.taskgraph.monitor import MonitorBank

MIN_OPENING = 0.010


def gap_monitor(mid="m", window=3, margin=0.002, recovery="r1", mode="missed_grasp"):
    """Value = MIN_OPENING - opening, so each step's value is set through the opening."""
    return Monitor(id=mid, failure_mode=mode, window=window, margin=margin, recovery=recovery,
                   check={"kind": "not_grasped", "arm": "right", "min_opening": MIN_OPENING})


def feats(value: float, cup=(0.0, 0.0, 0.0)) -> Features:
    arms = {} if math.isnan(value) else {"right": ArmState(eef=(0, 0, 0), opening=MIN_OPENING - value)}
    return Features(objects={"cup": ObjectState(centroid=cup)}, arms=arms)


def run(bank: MonitorBank, values) -> list[int]:
    return [i for i, v in enumerate(values) if bank.step(feats(v)) is not None]


def test_fires_on_exactly_the_wth_violated_step():
    for w in (1, 2, 3, 7):
        bank = MonitorBank([gap_monitor(window=w)])
        hits = run(bank, [0.005] * (w + 2))
        assert hits[0] == w - 1


def test_a_non_violated_step_resets_the_window():
    bank = MonitorBank([gap_monitor(window=3)])
    assert run(bank, [0.005, 0.005, 0.0, 0.005, 0.005, 0.005]) == [5]


def test_margin_is_strict():
    bank = MonitorBank([gap_monitor(window=2, margin=0.002)])
    assert run(bank, [0.002] * 10) == []  # exactly at the margin: not violated
    assert run(MonitorBank([gap_monitor(window=2, margin=0.002)]), [0.0021, 0.0021]) == [1]
    assert run(MonitorBank([gap_monitor(window=2, margin=0.002)]), [0.001] * 10) == []  # > 0 but within margin


def test_nan_breaks_the_streak():
    bank = MonitorBank([gap_monitor(window=2)])
    assert run(bank, [0.005, math.nan, 0.005, 0.005]) == [3]


def test_firing_names_mode_recovery_and_step():
    bank = MonitorBank([gap_monitor(mid="slow", window=4, recovery="ra", mode="slip"),
                        gap_monitor(mid="fast", window=2, recovery="rb", mode="drop")])
    assert bank.step(feats(0.005)) is None
    f = bank.step(feats(0.005))
    assert (f.monitor, f.failure_mode, f.recovery, f.step) == ("fast", "drop", "rb", 1)
    assert f.value == pytest.approx(0.005)
    assert bank.values == pytest.approx([0.005, 0.005])


def test_first_in_declaration_order_wins_a_tie():
    bank = MonitorBank([gap_monitor(mid="a", window=2, recovery=None), gap_monitor(mid="b", window=2)])
    bank.step(feats(0.005))
    f = bank.step(feats(0.005))
    assert f.monitor == "a" and f.recovery is None


def test_reset_clears_counters():
    bank = MonitorBank([gap_monitor(window=2)])
    bank.step(feats(0.005))
    bank.reset()
    assert bank.step(feats(0.005)) is None


def test_drift_reference_latched_at_edge_start_or_first_sight():
    m = Monitor(id="d", failure_mode="object_moved", window=1,
                check={"kind": "drift", "point": {"entity": "cup"}, "tol": 0.03, "axes": "xy"})
    bank = MonitorBank([m], start=feats(0.0, cup=(0.5, 0.0, 0.0)))
    assert bank.step(feats(0.0, cup=(0.52, 0.0, 0.0))) is None
    assert bank.step(feats(0.0, cup=(0.54, 0.0, 0.0))) is not None
    lost = Features(arms={"right": ArmState(eef=(0, 0, 0))})
    bank = MonitorBank([m], start=lost)  # cup unseen at start: latch when first seen
    assert bank.step(lost) is None
    assert bank.step(feats(0.0, cup=(0.2, 0.0, 0.0))) is None
    assert bank.step(feats(0.0, cup=(0.3, 0.0, 0.0))) is not None
