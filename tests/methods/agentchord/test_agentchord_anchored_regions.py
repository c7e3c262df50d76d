"""A region beside an object rides with it (rearrange-table under `shift`: the plate slid while the fork was on its
way, and a fork set beside the plate's old place must neither pass the check nor be aimed there)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from kintsugi.methods.agentchord.aim import region_call
from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.templates import node_constraints
from kintsugi.methods.agentchord.types import SeenObject
from kintsugi.taskgraph.constraints import InRegion
from kintsugi.taskgraph.features import Features


def _at(x: float, y: float) -> SimpleNamespace:
    return SimpleNamespace(centroid=(x, y, 0.01))


def _beside() -> InRegion:
    return InRegion(point={"entity": "fork"}, lo=(0.46, 0.14, -1.0), hi=(0.54, 0.22, 2.0), anchor="plate",
                    anchor_at=(0.5, 0.0))


def test_the_region_follows_its_anchor() -> None:
    c = _beside()
    assert c.evaluate(Features(objects={"plate": _at(0.5, 0.0), "fork": _at(0.5, 0.18)})) < 0
    slid = {"plate": _at(0.5, 0.06)}
    assert c.evaluate(Features(objects={**slid, "fork": _at(0.5, 0.18)})) > 0  # at the old place: not there
    assert c.evaluate(Features(objects={**slid, "fork": _at(0.5, 0.24)})) < 0  # beside where the plate is now
    assert math.isnan(c.evaluate(Features(objects={"fork": _at(0.5, 0.18)})))  # anchor unseen: undecided
    assert ("plate", "point", None) in set(c.refs())


def test_anchor_and_where_it_was_come_together() -> None:
    with pytest.raises(ValueError, match="together"):
        InRegion(point={"entity": "fork"}, lo=(0, 0, 0), hi=(1, 1, 1), anchor="plate")


def test_a_place_beside_an_object_compiles_to_an_anchored_region() -> None:
    seen = {"plate": SeenObject(name="plate", visible=True, centroid=(0.5, 0.01, 0.01)),
            "fork": SeenObject(name="fork", visible=True, centroid=(0.3, 0.25, 0.01))}
    where = {"beside_left(plate)": (0.5, 0.19)}
    cs, _ = node_constraints(TABLETOP_DOMAIN, [("in_region", "fork", "beside_left(plate)")], seen, where)
    (region,) = [InRegion(**c) for c in cs if c["kind"] == "in_region"]
    assert region.anchor == "plate" and region.anchor_at == (0.5, 0.01)
    cs, _ = node_constraints(TABLETOP_DOMAIN, [("in_region", "fork", "target")], seen, {"target": (0.5, 0.2)})
    assert all(c.get("anchor") is None for c in cs)  # a painted region stays where it is


class _Robot:
    def __init__(self, plate: tuple[float, float]) -> None:
        self.plate = plate

    def arm_state(self, arm: str) -> SimpleNamespace:
        return SimpleNamespace(touching={"fork": 2}, held=frozenset({"fork"}))

    def features(self, names) -> dict:  # noqa: ANN001
        return {"plate": SimpleNamespace(visible=True, centroid=(*self.plate, 0.01))}


def test_the_place_is_aimed_where_the_anchor_is_when_it_runs() -> None:
    node = SimpleNamespace(constraints=[_beside()])
    call = {"action": "place", "arm": "left", "x": 0.5, "y": 0.18}
    assert region_call(node, _Robot((0.5, 0.06)), call) == {**call, "y": 0.24}
    assert region_call(node, _Robot((0.5, 0.004)), call) == call  # within perception's noise: unchanged
