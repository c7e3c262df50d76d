"""An object that comes to rest in the open hand (a bottle dropped mid-pour, lying across the open fingers):
the conductor closes on it, turns its known top up and sets it down clear of every other object, instead of
re-grasping it from above (which lifted it with the hand and flung it out of reach)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kintsugi.methods.agentchord.settling import SET_DOWN_MARGIN_M, set_down_spots
from kintsugi.methods.agentchord.method import metrics_of
from kintsugi.perception.features import ObjectFeatures
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial


def _obj(name: str, x: float, y: float, length: float) -> ObjectFeatures:
    return ObjectFeatures(name=name, visible=True, n_points=100, fit="primitive", centroid=(x, y, 0.2),
                          extent=(length, 0.06, 0.06))


def test_straight_below_when_nothing_is_near() -> None:
    spots = set_down_spots(_obj("bottle", 0.45, -0.15, 0.2), [_obj("cup", 0.45, 0.3, 0.08)], np.zeros(3))
    assert spots[0] == pytest.approx((0.45, -0.15))


def test_beside_what_is_below() -> None:
    """The cup held just below the caught bottle: the first spot clears both half extents and the margin, and
    of the spots that near, the one nearer the arm's base (easier to reach)."""
    bottle, cup = _obj("bottle", 0.45, -0.12, 0.2), _obj("cup", 0.46, -0.05, 0.08)
    spots = set_down_spots(bottle, [cup], np.array([0.0, -0.3, 0.0]))
    first = np.array(spots[0])
    assert np.linalg.norm(first - [0.46, -0.05]) >= 0.1 + 0.04 + SET_DOWN_MARGIN_M - 1e-9
    assert np.linalg.norm(first - [0.45, -0.12]) == pytest.approx(0.1)
    assert first[1] < -0.12  # the side away from the cup, towards the right arm's base


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.2, 0.7), st.floats(-0.4, 0.4), st.floats(0.02, 0.3)), max_size=4),
       st.floats(0.2, 0.7), st.floats(-0.4, 0.4))
def test_every_spot_is_clear_and_nearest_first(others, x, y) -> None:  # noqa: ANN001
    obj = _obj("bottle", x, y, 0.2)
    rest = [_obj(f"o{i}", *o) for i, o in enumerate(others)]
    spots = set_down_spots(obj, rest, np.array([0.0, -0.3, 0.0]))
    for p in spots:
        for o in rest:
            assert np.linalg.norm(np.array(p) - o.centroid[:2]) >= 0.1 + o.extent[0] / 2 + SET_DOWN_MARGIN_M - 1e-9
    d = [round(float(np.hypot(p[0] - x, p[1] - y)), 3) for p in spots]
    assert d == sorted(d)


@pytest.mark.slow
@pytest.mark.parametrize(("task", "seed", "most_steps"), [("pour-dual", 86, 2100), ("pour-single", 1, 1300)])
def test_a_bottle_caught_in_the_open_hand_is_stood_up_clear_of_the_rest(task: str, seed: int, most_steps: int) -> None:
    """At drop p 0.10 the bottle drops as the hand turns back from pouring and stays across the open fingers.
    Pour-dual seed 86: the re-grasp used to carry it off and fling it 0.76 m out (an IK failure ended the
    trial). Pour-single seed 1: the turn used the bottle's pose in the hand from before it slipped, set it
    down 20 degrees off and it fell over (2330 steps); its pose is now read again after the close."""
    r = run_trial(TrialSpec(task=task, method="agentchord", variant="default", condition="drop", seed=seed,
                            overrides={"disturbance.drop_p": 0.1}))
    assert r.error is None, r.error
    assert any(e.kind == "caught" and "bottle" in e.detail for e in r.events)
    assert r.success and r.framework_success
    m = metrics_of(r)
    assert m.recoveries == 1 and m.runtime_reasoning_calls == 0 and m.episode_steps < most_steps
