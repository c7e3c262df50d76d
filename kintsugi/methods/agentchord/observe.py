"""The robot's observation in the two shapes system B's reasoning and monitors read: the roles' typed
`SeenObject`/`SeenArm` (perceived features and the arms' own sensors, never truth) and the monitors'
`Features` vector (Eq. 1)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np

from kintsugi.methods.agentchord.types import SeenArm, SeenObject
from kintsugi.taskgraph.features import ArmState, Features

ARMS = ("left", "right")


def seen_objects(objects: dict[str, Any]) -> list[SeenObject]:
    out = []
    for name, f in objects.items():
        ex = f.extremes or {}
        out.append(SeenObject(
            name=name, visible=bool(f.visible), centroid=f.centroid,
            top_z=ex["top"][2] if "top" in ex else None, bottom_z=ex["bottom"][2] if "bottom" in ex else None,
            tilt_deg=f.tilt_deg, upright=f.upright, extent=f.extent, extremes=dict(ex),
            axis=f.axis if f.upright is not None else None, n_points=int(f.n_points)))
    return out


def seen_arms(arms: dict[str, Any]) -> list[SeenArm]:
    return [SeenArm(name=name, tcp_pos=a.tcp_pos, gripper_opening_m=a.gripper_opening_m,
                    gripper_closed=a.gripper_closed, holding=sorted(a.held))
            for name, a in arms.items()]


def arm_features(arm: Any) -> ArmState:
    """One arm's proprioception as the monitors read it: tool position, opening, commanded state, contacts."""
    return ArmState(eef=arm.tcp_pos, opening=float(arm.gripper_opening_m), closed=bool(arm.gripper_closed),
                    touching=arm.held)


@dataclass(frozen=True, slots=True)
class AxisFree:
    """A perceived object whose principal axis perception could not define (e.g. a raw, unfitted cloud):
    axis-based checks (upright, tilted) read it as undecided (NaN), not as a measurement."""

    centroid: Any
    n_points: int
    extremes: Any
    axis: None = None
    extent: Any = None
    """Its perceived spans (a cube's footprint, for `within` and `on`)."""
    fit: str | None = None
    """How perception described it (`raw`: an unfitted cloud, whose `centre` a point reads from its axis ends)."""


def monitored(f: Any) -> Any:
    return (AxisFree(f.centroid, f.n_points, f.extremes, None, getattr(f, "extent", None), getattr(f, "fit", None))
            if f.upright is None else f)


def with_tracked_top(f: Any, top: Any) -> Any:
    """The features plus extreme `tracked_top`: the end of the perceived axis on the side of the top the robot
    keeps track of (`Tops`: its encoders while it held the object, continuity while it fell). A bottle that
    landed on its head with its cap hidden (in a cup) looks upright to the cameras; the robot knows better."""
    ex = getattr(f, "extremes", None) or {}
    if top is None or f.axis is None or "cap" in ex or "axis_pos" not in ex or "axis_neg" not in ex:
        return f
    end = ex["axis_pos"] if float(np.dot(f.axis, top)) >= 0.0 else ex["axis_neg"]
    return f.model_copy(update={"extremes": {**ex, "tracked_top": end}})


def features(robot: Any, objects: Iterable[str] | None = None, cached: dict[str, Any] | None = None,
             tops: Mapping[str, Any] | None = None) -> Features:
    """The feature vector now: objects perceived (or `cached` when perception is not re-run this step), with
    the robot's tracked top of each object it keeps one for (`tops`)."""
    objs = cached if cached is not None else robot.features(objects)
    tops = tops or {}
    visible = {k: monitored(with_tracked_top(f, tops.get(k))) for k, f in objs.items()
               if f.visible and f.centroid is not None}
    return Features(objects=visible, arms={a: arm_features(robot.arm_state(a)) for a in ARMS})
