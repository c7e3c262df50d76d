"""The method's side relations and `on_table` read the scorers' bounds shrunk by perception's measured error
(`RELATION_MARGIN_M` on a relative centre, `ON_TABLE_MARGIN_M` on a resting object's lowest point): never looser
than the scorer, and no stricter than that error requires."""

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


def test_on_table_is_the_scorers_bound_shrunk_by_the_perception_margin() -> None:
    m = domain.ON_TABLE_MARGIN_M
    assert 0.0 < m < judge.TABLE_Z_M
    assert domain.ON_TABLE_M == pytest.approx((-(judge.TABLE_Z_M - m), judge.TABLE_Z_M - m))


@pytest.mark.parametrize("name", ["on_table", "beside"])
def test_the_perceived_on_table_check_accepts_only_bottoms_the_scorer_accepts_beyond_the_margin(name: str) -> None:
    from types import SimpleNamespace

    from kintsugi.taskgraph.constraints import InRegion
    from kintsugi.taskgraph.features import Features

    spec = next(p for p in domain.PREDICATES if p.name == name)
    c = next(c for c in spec.constraints if c["kind"] == "in_region")
    check = InRegion.model_validate({**c, "point": {**c["point"], "entity": "x"}})

    def holds(z: float) -> bool:
        o = SimpleNamespace(centroid=(0.4, 0.1, z + 0.03), visible=True, extremes={"bottom": (0.4, 0.1, z)})
        return check.evaluate(Features(objects={"x": o})) <= 0.0

    m, tol = domain.ON_TABLE_MARGIN_M, judge.TABLE_Z_M
    for z in (-(tol - 1.01 * m), 0.0, 0.003, tol - 1.01 * m):
        assert holds(z)
    for z in (-(tol + 0.001), -(tol - 0.99 * m), tol - 0.99 * m, tol + 0.001, 0.02):
        assert not holds(z)


@pytest.mark.parametrize("task", ["rearrange-table", "coffee-tray", "handover-block"])
def test_in_region_is_the_task_statements_region_shrunk_by_the_perception_margin(task: str) -> None:
    """Each region the task states is checked inside its own half-extents less the margin, so a centre the
    method reads inside it lies inside the scorer's region too (a fixed 4 cm would let a spoon 3.3 cm off a
    2.5 cm region count as placed)."""
    from types import SimpleNamespace

    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS
    from kintsugi.methods.agentchord.compile import task_region_sizes
    from kintsugi.methods.agentchord.facts import place_table
    from kintsugi.methods.agentchord.templates import node_constraints

    load_builtins()
    t = TASKS.get(task).factory()
    cfg = t.config({})
    sizes = task_region_sizes(t.spec, cfg, domain.TABLETOP_DOMAIN)
    assert sizes, f"{task} states regions"
    plate = SimpleNamespace(centroid=(0.45, 0.0, 0.01))
    for place, half in sizes.items():
        declared = [r for n, r in cfg.targets.items() if n in t.spec.targets and tuple(r.half_m) == half]
        assert declared, (place, half)
        where = place_table([place], domain.TABLETOP_DOMAIN, {"plate": plate}, {place: (0.4, -0.25)}, sizes)
        (c,), _ = node_constraints(domain.TABLETOP_DOMAIN, [("in_region", "x", place)], {}, where)
        centre = where[place]
        for i in (0, 1):
            assert c["hi"][i] - centre[i] == pytest.approx(half[i] - domain.RELATION_MARGIN_M)
            assert centre[i] - c["lo"][i] == pytest.approx(half[i] - domain.RELATION_MARGIN_M)


def test_in_region_reads_where_the_object_is_not_where_its_cloud_leans() -> None:
    """An unfitted cloud's mean leans towards a wide end (a fork's head: about 2 cm); the check reads the middle
    of the perceived axis ends, so a fork 5.7 cm off a region whose bound is 3.5 cm is out even though its
    cloud's mean is 3.3 cm off."""
    from types import SimpleNamespace

    from kintsugi.methods.agentchord.facts import place_table
    from kintsugi.methods.agentchord.templates import node_constraints
    from kintsugi.taskgraph.constraints import InRegion
    from kintsugi.taskgraph.features import Features

    where = place_table(["target"], domain.TABLETOP_DOMAIN, {}, {"target": (0.5, 0.2)}, {"target": (0.04, 0.025)})
    (c,), _ = node_constraints(domain.TABLETOP_DOMAIN, [("in_region", "fork", "target")], {}, where)
    check = InRegion.model_validate(c)

    def fork(middle_x: float, lean: float) -> SimpleNamespace:
        ends = {"axis_pos": (middle_x + 0.06, 0.2, 0.004), "axis_neg": (middle_x - 0.06, 0.2, 0.004)}
        return SimpleNamespace(centroid=(middle_x + lean, 0.2, 0.004), visible=True, extremes=ends, axis=None,
                               fit="raw")

    assert check.evaluate(Features(objects={"fork": fork(0.5 - 0.057, 0.024)})) > 0.0
    assert check.evaluate(Features(objects={"fork": fork(0.5 - 0.02, 0.024)})) <= 0.0
    no_axis = SimpleNamespace(centroid=(0.5, 0.2, 0.004), visible=True, extremes={}, axis=None, fit="raw")
    assert check.evaluate(Features(objects={"fork": no_axis})) <= 0.0  # no axis ends: its centroid
    fitted = fork(0.5 - 0.057, 0.057)  # a fitted shape: its centroid, whatever its ends (hands may hide one)
    fitted.fit = "primitive"
    assert check.evaluate(Features(objects={"fork": fitted})) <= 0.0
