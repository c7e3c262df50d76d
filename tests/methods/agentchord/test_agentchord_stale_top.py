"""A top tracked for an object that turned while no hand held it and no settle watched it (knocked over while
both hands were busy) is read again before a hand takes it (`Tops.refresh`). Taken with the stale top (up), a
top-down grasp recorded it along the approach axis, and the stand-up turned the bottle no nearer upright
(pour-dual development seed 41017 under `all`). A container's fitted opening signs its top as a bottle's cap
does: a cup that tipped out of the hand and fell was stood up on its rim (seed 41008 under `all`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from kintsugi.methods.agentchord.tops import Tops

UP = np.array([0.0, 0.0, 1.0])


@dataclass
class _Seen:
    axis: tuple[float, float, float] | None
    centroid: tuple[float, float, float] | None = (0.3, -0.1, 0.03)
    upright: bool | None = False
    visible: bool = True
    extremes: dict = field(default_factory=dict)


def test_a_lying_object_whose_tracked_top_is_still_up_is_read_again_from_its_cap() -> None:
    tops = Tops()
    tops.world["bottle"] = UP.copy()
    cap = (0.3 - 0.09, -0.1, 0.03)  # the cap at the -x end
    tops.refresh({"bottle": _Seen(axis=(1.0, 0.0, 0.0), extremes={"cap": cap})})
    assert np.allclose(tops.world["bottle"], [-1.0, 0.0, 0.0])


def test_an_object_whose_axis_still_agrees_keeps_its_tracked_top() -> None:
    tops = Tops()
    tops.world["bottle"] = UP.copy()
    tilted = np.array([np.sin(np.radians(20.0)), 0.0, np.cos(np.radians(20.0))])
    tops.refresh({"bottle": _Seen(axis=tuple(tilted), upright=True)})
    assert np.allclose(tops.world["bottle"], UP)  # within STALE_DEG: the estimate stands
    tops.refresh({"bottle": _Seen(axis=None)})
    assert np.allclose(tops.world["bottle"], UP)  # nothing perceived: nothing changes


def test_without_a_cap_the_lying_axis_is_signed_like_the_stale_top() -> None:
    tops = Tops()
    tops.world["bottle"] = np.array([0.0, 0.0, 1.0])
    tops.refresh({"bottle": _Seen(axis=(-0.99, 0.0, -0.1))})
    top = tops.world["bottle"]
    assert abs(top[2]) < 0.2 and top[2] >= 0.0  # lying now; the end that was higher


def test_a_containers_fitted_opening_signs_its_top_as_a_cap_does() -> None:
    tops = Tops()
    tops.world["cup"] = np.array([1.0, 0.0, 0.0])  # the top the hand last had: carried over wrongly by a slip
    opening = (0.3 - 0.045, -0.1, 0.03)  # the open end at -x: it fell over that way
    tops.observe({"cup": _Seen(axis=(1.0, 0.0, 0.0), extremes={"opening": opening})})
    assert np.allclose(tops.world["cup"], [-1.0, 0.0, 0.0])


def test_before_a_grasp_only_the_objects_it_takes_and_no_hand_holds_are_read() -> None:
    tops = Tops()
    tops.world.update(bottle=UP.copy(), cup=UP.copy())
    tops.in_hand[("left", "cup")] = UP.copy()
    asked: list[set[str]] = []

    def perceive(names: set[str]) -> dict:
        asked.append(set(names))
        return {n: _Seen(axis=(1.0, 0.0, 0.0), extremes={"cap": (0.39, -0.1, 0.03)}) for n in names}

    tops.before_grasp({"action": "move_by_offset", "arm": "right"}, perceive)
    assert asked == []
    tops.before_grasp({"action": "drive", "left": {"action": "grasp", "arm": "left", "obj": "cup"},
                       "right": {"action": "grasp", "arm": "right", "obj": "bottle"}}, perceive)
    assert asked == [{"bottle"}] and np.allclose(tops.world["bottle"], [1.0, 0.0, 0.0])
