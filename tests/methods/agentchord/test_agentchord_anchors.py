"""The verdict refuses a goal region placed by an object that an outside hand has since slid (rearrange-table
under `shift`: the fork was set beside the plate's old place and the region check, placed there too, passed)."""

from __future__ import annotations

from types import SimpleNamespace

from kintsugi.methods.agentchord.anchors import stale_regions
from kintsugi.taskgraph.constraints import InRegion


def _goal() -> SimpleNamespace:
    beside = InRegion(point={"entity": "fork"}, lo=(0.46, 0.14, -1.0), hi=(0.54, 0.22, 2.0))
    table = InRegion(point={"entity": "fork", "feature": "bottom"}, lo=(-2.0, -2.0, -0.02), hi=(2.0, 2.0, 0.03))
    return SimpleNamespace(constraints=[beside, table])


def _at(x: float, y: float) -> SimpleNamespace:
    return SimpleNamespace(centroid=(x, y, 0.01))


def test_a_slid_anchor_makes_its_region_stale() -> None:
    seen = {"plate": (0.5, 0.0), "fork": (0.3, 0.25)}
    notes = stale_regions(_goal(), seen, {"fork": (0.3, 0.25)}, {"plate": _at(0.5, 0.05), "fork": _at(0.5, 0.18)})
    assert len(notes) == 1 and notes[0].startswith("plate moved 5.0 cm")


def test_no_note_when_the_anchor_stayed_or_a_hand_moved_it_or_it_is_far() -> None:
    seen = {"plate": (0.5, 0.0)}
    assert stale_regions(_goal(), seen, {}, {"plate": _at(0.51, 0.0)}) == []  # 1 cm: perception, not a slide
    assert stale_regions(_goal(), seen, {"plate": (0.5, 0.0)}, {"plate": _at(0.5, 0.1)}) == []  # this robot took it
    far = {"cup": (0.5, -0.6)}
    assert stale_regions(_goal(), far, {}, {"cup": _at(0.5, -0.5)}) == []  # nowhere near the region
