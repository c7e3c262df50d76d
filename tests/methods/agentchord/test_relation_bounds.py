"""The method's side relations read the scorers' bounds shrunk by perception's measured error on a relative
centre (`RELATION_MARGIN_M`): never looser than the scorer, and no stricter than that error requires."""

from __future__ import annotations

import pytest

from kintsugi.methods.agentchord import domain
from kintsugi.worlds.tabletop import judge


def test_side_bounds_are_the_scorers_shrunk_by_the_perception_margin() -> None:
    m = domain.RELATION_MARGIN_M
    assert 0.0 < m <= 0.01
    assert domain.SIDE_M == pytest.approx((judge.SIDE_M[0] + m, judge.SIDE_M[1] - m))
    assert domain.SIDE_ALONG_M == pytest.approx(judge.SIDE_ALONG_M - m)
    assert domain.BESIDE_M_RANGE == pytest.approx((judge.BESIDE_M[0] + m, judge.BESIDE_M[1] - m))
    assert domain.SIDE_M[0] < domain.SIDE_AIM_M < domain.SIDE_M[1]


@pytest.mark.parametrize("side", ["left_of", "right_of"])
def test_the_perceived_check_accepts_what_the_scorer_accepts_beyond_the_margin(side: str) -> None:
    from kintsugi.taskgraph.constraints import Offset

    spec = next(p for p in domain.PREDICATES if p.name == side)
    c = spec.constraints[0]
    check = Offset.model_validate({**c, "a": {"entity": "x"}, "b": {"entity": "y"}})
    sign = 1.0 if side == "left_of" else -1.0
    m = domain.RELATION_MARGIN_M
    lo, hi = judge.SIDE_M

    def holds(dx: float, dy: float) -> bool:
        from kintsugi.taskgraph.features import Features
        from types import SimpleNamespace

        def obj(x: float, y: float):  # noqa: ANN202
            return SimpleNamespace(centroid=(x, y, 0.05), visible=True, extremes={})
        f = Features(objects={"x": obj(0.4 + dx, sign * dy), "y": obj(0.4, 0.0)})
        return check.evaluate(f) <= 0.0

    for dy in (lo + 1.01 * m, 0.15, hi - 1.01 * m):
        assert holds(0.0, dy) and holds(judge.SIDE_ALONG_M - 1.01 * m, dy)
    for dy in (lo - 0.001, lo + 0.99 * m, hi - 0.99 * m, hi + 0.001):
        assert not holds(0.0, dy)
    assert not holds(judge.SIDE_ALONG_M - 0.99 * m, 0.15)
