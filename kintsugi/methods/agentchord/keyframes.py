"""Keyframes of the tabletop's free moves (Eq. 9): where the grasp point must go so that the target node's
constraints hold, with the held object carried rigidly, clear of the other objects, within reach, checked
by the arm's own IK. The composer's intended target (object + offset) is the regularizer's reference.

Only `move_to_obj` edges have a free keyframe: grasp, place and rotate_eef compute their targets from
perception inside the robot's atomic action, so they are verified there (an unreachable one fails the action
with the IK's message).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from kintsugi.core.errors import KintsugiError
from kintsugi.taskgraph.features import ArmState, Features
from kintsugi.taskgraph.keyframe import Keyframe, solve_keyframe
from kintsugi.taskgraph.model import Edge, Node

CLEARANCE_M = 0.02
"""A carried object's bottom passes at least this far above any object it is over."""
PENALTY_WEIGHT = 1e3


class KeyframeError(KintsugiError):
    """No feasible keyframe for a node: the message is the solver's (or the IK's)."""


@dataclass(frozen=True)
class Moved:
    """An object's features shifted by a displacement (a held object following the hand)."""

    centroid: tuple
    axis: tuple | None
    n_points: int
    extremes: Mapping[str, tuple] = field(default_factory=dict)


def _shift(f: Any, d: np.ndarray) -> Moved:
    ex = {k: tuple(np.asarray(v) + d) for k, v in (f.extremes or {}).items()}
    return Moved(tuple(np.asarray(f.centroid) + d), f.axis, max(int(f.n_points), 1), ex)


def _radius(f: Any) -> float:
    return float(f.extent[1]) / 2 if f.extent is not None else 0.03


class TabletopKeyframes:
    """Solves and IK-checks keyframes for one trial's robot (its config's arms)."""

    def __init__(self, cfg: Any) -> None:
        from kintsugi.worlds.tabletop.arm_model import base_position
        from kintsugi.worlds.tabletop.ik import ArmIK

        self.cfg = cfg
        self.iks = {a: ArmIK(cfg.robot, cfg.motion, a) for a in ("left", "right")}
        r = cfg.robot
        self.reach = r.upper_arm_m + r.forearm_m + r.wrist_m + r.flange_to_grasp_m
        self.shoulders = {a: np.array(base_position(r, a)) + np.array([0.0, 0.0, r.shoulder_height_m])
                          for a in ("left", "right")}
        m = cfg.motion
        self.bounds = [tuple(m.workspace_x_m), tuple(m.workspace_y_m), tuple(m.workspace_z_m)]

    def move_target(self, edge: Edge, node: Node, objects: Mapping[str, Any], held: Mapping[str, np.ndarray],
                    arm_state: Any, last: np.ndarray | None = None) -> tuple[Keyframe, dict]:
        """Keyframe for a one-action `move_to_obj` edge and the `move_to_target` call that reaches it.

        `held`: object -> its centroid minus the grasp point (where it sits in the hand). Raises KeyframeError
        with the solver's or the IK's message when there is none."""
        from kintsugi.worlds.tabletop.planning import Planner, rpy_matrix

        act = edge.actions[0]
        arm, target = act.args["arm"], act.args["obj"]
        f = objects.get(target)
        if f is None or f.centroid is None:
            raise KeyframeError(f"edge {edge.id!r}: {target} is not visible, no keyframe for {node.id!r}")
        offset = np.array(act.args.get("offset", (0.0, 0.0, 0.0)), float)
        reference = np.array(f.centroid) + Planner.object_frame(f) @ offset
        others = {k: v for k, v in objects.items() if k not in held and v.centroid is not None}

        def predict(x: np.ndarray) -> Features:
            objs: dict[str, Any] = dict(others)
            for k, off in held.items():
                if k in objects and objects[k].centroid is not None:
                    objs[k] = _shift(objects[k], x + off - np.array(objects[k].centroid))
            return Features(objects=objs, arms={arm: ArmState(eef=tuple(x), opening=arm_state.gripper_opening_m,
                                                              closed=arm_state.gripper_closed,
                                                              touching=frozenset(held))})

        shoulder = self.shoulders[arm]

        def reach(x: np.ndarray) -> float:
            return PENALTY_WEIGHT * max(0.0, float(np.linalg.norm(x - shoulder)) - self.reach) ** 2

        def clear(x: np.ndarray) -> float:
            total = 0.0
            for k, off in held.items():
                h = objects.get(k)
                if h is None or h.centroid is None or "bottom" not in h.extremes:
                    continue
                c = x + off
                bottom = h.extremes["bottom"][2] - h.centroid[2] + c[2]
                total += max(0.0, 0.01 - bottom) ** 2
                for o in others.values():
                    if np.hypot(*(c[:2] - np.array(o.centroid[:2]))) < _radius(h) + _radius(o) + 0.01:
                        top = o.extremes.get("top", o.centroid)[2]
                        total += max(0.0, top + CLEARANCE_M - bottom) ** 2
            return PENALTY_WEIGHT * total

        kf = solve_keyframe(node.constraints, predict, reference, self.bounds, (reach, clear), last=last)
        if not kf.ok:
            raise KeyframeError(f"node {node.id!r}: {kf.message}")
        rpy = act.args.get("rpy_deg")
        rot = rpy_matrix(tuple(rpy)) if rpy is not None else None
        if rot is not None:
            ik = self.iks[arm].solve(kf.x, rot, self.iks[arm].home)
            if not ik.ok:
                raise KeyframeError(f"node {node.id!r}: keyframe {np.round(kf.x, 3).tolist()} {ik.message()}")
        call = {"action": "move_to_target", "arm": arm, "xyz": tuple(round(float(v), 4) for v in kf.x)}
        if rpy is not None:
            call["rpy_deg"] = tuple(float(v) for v in rpy)
        return kf, call
