"""The tabletop world's names as a task-graph Vocabulary: its atomic actions (checked by the world's own
action parser, so a graph never holds a call the robot would refuse), the scene's objects, perceived
feature names and the two arms."""

from __future__ import annotations

from typing import Any, Callable, Sequence

from kintsugi.taskgraph.vocabulary import Vocabulary

FEATURES = frozenset({"centroid", "centre", "axis", "n_points", "extent", "top", "bottom", "axis_pos", "axis_neg",
                      "opening", "cap"})
"""ObjectFeatures' vectors: centroid, axis, spans (`extent`) and the extremes perception reports; `centre`, the
middle of the axis ends (a point constraint's reading of where an object is)."""


def _checker(name: str, objects: Sequence[str]) -> Callable[[dict[str, Any]], None]:
    from kintsugi.worlds.tabletop.actions import parse_action

    def check(args: dict[str, Any]) -> None:
        if "action" in args:
            raise ValueError("the action's name goes in `name`, not in its arguments")
        parse_action({"action": name, **args}, objects)

    return check


def tabletop_vocabulary(objects: Sequence[str]) -> Vocabulary:
    from kintsugi.worlds.tabletop.actions import ACTION_NAMES

    return Vocabulary(actions={n: _checker(n, objects) for n in ACTION_NAMES}, objects=frozenset(objects),
                      features=FEATURES)
