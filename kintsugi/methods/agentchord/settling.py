"""Waiting for the scene to come to rest, with an open hand, before a recovery or the goal check reads it.

A dropped object falls, rolls and rocks for a while; a recovery whose re-grasp aimed at where it was falling
would miss it. The hand opens and perception reads the watched objects until two consecutive pairs of reads
agree (centroids within SETTLE_M, principal axes within SETTLE_DEG). An object that came to rest in the open
hand instead of on the table is closed on, turned top up when its top is known, and set down clear of the
others (`set_down_spots`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.methods.agentchord.conducting import objects_of
from kintsugi.perception.features import ObjectFeatures
from kintsugi.taskgraph.model import Edge


SETTLE_M = 0.0003
"""Two reads of every watched centroid this close (about 0.1 s apart)... (renders are deterministic, so a
still object reads the same twice; a bottle rocking on its base after a drop moves its centroid ~1 mm)"""
SETTLE_DEG = 0.2
"""...and of every watched principal axis this close in angle: the objects are at rest."""
SETTLE_READS = 2
"""Consecutive still pairs required (one pair can alias with a rocking object's period)."""
SETTLE_TRIES = 25
CAUGHT_CLEAR_M = 0.02
"""An object whose lowest perceived point is this far above the table does not rest on it."""
MAX_SET_DOWNS = 2
SET_DOWN_TRIES = 6
SET_DOWN_MARGIN_M = 0.03
"""A caught object is set down this far (beyond both objects' half extents) from every other object."""


class Settling:
    """The conductor's settle (a mixin of `Conductor`: it runs actions through the conductor's `_execute` and
    reads through its robot, top and head trackers)."""

    robot: Any
    log: Any
    goal_objects: set[str]

    def wait_still(self, arm: str, objs: set[str], edge: Edge) -> bool:
        """True once the objects are at rest; False if they still move after SETTLE_TRIES reads."""
        if not objs:
            return True
        prev, still, set_downs = None, 0, 0
        for _ in range(SETTLE_TRIES):
            self._execute(edge, "open_gripper", {"arm": arm})
            now = self.robot.features(objs)
            self.tops.observe(now)
            self.heads.observe(now)
            seen = [now[k] for k in sorted(objs) if now[k].centroid is not None]
            pts = np.array([f.centroid for f in seen], dtype=float).reshape(-1, 3)  # none seen: (0, 3)
            axes = [None if f.axis is None else np.asarray(f.axis, dtype=float) for f in seen]
            moved = prev is None or pts.shape != prev[0].shape or not np.all(np.linalg.norm(pts - prev[0], axis=1) < SETTLE_M)
            if not moved:
                for a, b in zip(axes, prev[1]):
                    if (a is None) != (b is None):
                        moved = True
                    elif a is not None:
                        cos = abs(float(a @ b)) / max(float(np.linalg.norm(a) * np.linalg.norm(b)), 1e-12)
                        moved = moved or np.degrees(np.arccos(min(1.0, cos))) > SETTLE_DEG
            still = 0 if moved else still + 1
            if still >= SETTLE_READS:
                if set_downs < MAX_SET_DOWNS and self._set_down_caught(arm, now, edge):
                    set_downs, prev, still = set_downs + 1, None, 0
                    continue
                if hasattr(self.robot, "control_steps"):
                    self._rested = (self.robot_steps(), frozenset(objs))
                return True
            prev = (pts, axes)
        return False

    def _settle_hands(self, edge: Edge) -> None:
        """Before a re-plan reads the scene: a hand closed on nothing it holds opens, and the objects come to rest.
        A recovery given up in mid-grasp can leave an object falling, or resting on closed fingers, which no
        fact of the planner's describes (a bottle neither held nor on the table: "never achievable")."""
        for arm in ("left", "right"):
            state = self.robot.arm_state(arm)
            if state.gripper_closed and not state.held:
                self.wait_still(arm, self.goal_objects | objects_of(edge), edge)

    def _set_down_caught(self, arm: str, seen: dict, edge: Edge) -> bool:
        """An object that came to rest in the open hand (both finger pads touch it, and it hangs clear of the
        table) is closed on, turned top up when its top is known (its pose in the hand read again first), and set
        down at the nearest spot clear of every other object; True if one was. A bottle dropped while the hand
        was turned over to pour fell across the open fingers and stayed there; the re-grasp's rise to its pose
        above carried it along and flung it out of reach (pour-dual seeds 86 and 88). Set down straight below,
        it lay where the other hand was lowering the cup."""
        touching = self.robot.arm_state(arm).touching
        caught = [k for k in sorted(seen) if touching.get(k) == 2 and seen[k].centroid is not None
                  and seen[k].extremes and seen[k].extremes["bottom"][2] > CAUGHT_CLEAR_M]
        if not caught:
            return False
        obj = caught[0]
        self.log.event(self.robot.sim_time, "caught", f"{obj} rests in the open {arm} hand: set it down")
        self._execute(edge, "close_gripper", {"arm": arm})
        self.tops.regrip(arm, obj, self.robot.features({obj}), self.robot.arm_state(arm))
        turn = self.synthesis.upright_call({"action": "rotate_eef", "arm": arm, "angle_deg": 0.0, "axis": "closing"})
        if turn["action"] == "move_by_offset":  # its top is known: stand it on its base
            self._execute(edge, "move_by_offset", {k: v for k, v in turn.items() if k != "action"})
        others = [f for k, f in self.robot.features().items() if k != obj and f.centroid is not None]
        for x, y in set_down_spots(seen[obj], others, self.robot.bases[arm])[:SET_DOWN_TRIES]:
            if self._execute(edge, "place", {"arm": arm, "x": round(x, 4), "y": round(y, 4)}, unplanned_ok=True):
                return True
        self._execute(edge, "open_gripper", {"arm": arm})
        return True


def set_down_spots(obj: ObjectFeatures, others: list[ObjectFeatures], base: np.ndarray) -> list[tuple[float, float]]:
    """Table spots (x, y) to set a caught object down at, nearest first (ties: nearer the arm's base, easier
    to reach): below where it hangs, or rings around that 5 cm apart, clear of every other object's extent."""
    c = np.asarray(obj.centroid, dtype=float)[:2]
    half = max(obj.extent or (0.0,)) / 2.0
    spots = [c] + [c + r * np.array([np.cos(a), np.sin(a)]) for r in np.arange(0.05, 0.31, 0.05)
                   for a in np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)]
    spots.sort(key=lambda p: (round(float(np.linalg.norm(p - c)), 3), float(np.linalg.norm(p - base[:2]))))

    def clear(p: np.ndarray) -> bool:
        return all(np.linalg.norm(p - np.asarray(o.centroid, dtype=float)[:2])
                   >= half + max(o.extent or (0.0,)) / 2.0 + SET_DOWN_MARGIN_M for o in others)

    return [(float(p[0]), float(p[1])) for p in spots if clear(p)]
