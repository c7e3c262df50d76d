"""Aiming a place at another object where it is perceived when the place runs (edge synthesis, Eq. 10)."""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.taskgraph.model import Node

RE_AIM_M = 0.01
"""A place toward another object is re-aimed when that object is perceived this far from where the graph saw it."""


def relation_call(node: Node, robot: Any, seen: dict[str, tuple[float, float]], call: dict) -> dict:
    """A place toward a relation with another object (`on`, `inside`, `left_of`, `right_of`, `beside`: the target
    node's `within`, `offset` or `spacing` checks from the held object to it), aimed at that object where it is
    perceived now. The compiled target came from the observation the graph was filled from (`seen`: object ->
    its centroid's x, y there); the object may have been slid or knocked since. A stacking place (its bottom to
    the support's top) also takes the support's top as perceived now. Unchanged when the object moved less
    than RE_AIM_M, or is not seen."""
    held = set(robot.arm_state(call["arm"]).held)
    ref, onto = None, False
    for c in node.constraints:
        if c.kind == "within" and c.point.entity in held and c.container not in held:
            ref = c.container
        elif c.kind in ("offset", "spacing") and c.a.entity in held and c.b.entity not in held:
            ref = c.b.entity
            onto |= c.kind == "offset" and c.a.feature == "bottom" and c.b.feature == "top"
    if ref is None or ref not in seen:
        return call
    f = robot.features({ref}).get(ref)
    if f is None or not f.visible or f.centroid is None:
        return call
    dx, dy = float(f.centroid[0]) - seen[ref][0], float(f.centroid[1]) - seen[ref][1]
    if np.hypot(dx, dy) < RE_AIM_M:
        return call
    out = {**call, "x": round(call["x"] + dx, 4), "y": round(call["y"] + dy, 4)}
    top = (f.extremes or {}).get("top")
    if onto and top is not None:
        out["z_offset"] = round(max(0.0, float(top[2])), 4)
    return out


def region_call(node: Node, robot: Any, call: dict) -> dict:
    """A place into a region that rides with another object (the target node's anchored `in_region` on the held
    object: "to the left of the plate"), shifted by how far that object is perceived to have moved since the
    region was placed. Unchanged when it moved less than RE_AIM_M, or is not seen."""
    held = set(robot.arm_state(call["arm"]).held)
    for c in node.constraints:
        if c.kind != "in_region" or c.anchor is None or c.point.entity not in held or c.anchor in held:
            continue
        f = robot.features({c.anchor}).get(c.anchor)
        if f is None or not f.visible or f.centroid is None:
            return call
        dx, dy = float(f.centroid[0]) - c.anchor_at[0], float(f.centroid[1]) - c.anchor_at[1]
        if np.hypot(dx, dy) < RE_AIM_M:
            return call
        return {**call, "x": round(call["x"] + dx, 4), "y": round(call["y"] + dy, 4)}
    return call
