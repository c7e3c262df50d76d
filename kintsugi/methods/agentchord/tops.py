"""Which end of each object is its top, kept by the conductor from what the robot senses.

Perception gives an object's principal axis without a sign. A bottle's painted cap, when the cameras see it
(perception's extreme `cap`), says which end is its top outright, as a container's fitted open end does
(extreme `opening`, which the `upright` check reads as a container's top too). When a hand hides it, the robot can still
know: an object first seen standing has its top up; while a hand holds it, its top turns with the hand (joint encoders);
when it leaves the hand, its top is where the hand last had it; and while it falls and rolls, each perceived
axis is signed to agree with the previous estimate (the settle reads come every ~0.1 s, well under the time
a falling object needs to turn by 90 degrees). Standing a fallen object up uses this to turn its top up,
not down. No simulator state is read: arm poses, finger-pad touch and perceived axes only.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
from scipy.spatial.transform import Rotation

from kintsugi.taskgraph.geometry import head_yaw_deg

UP = np.array([0.0, 0.0, 1.0])
CAP_ALONG_M = 0.02
"""A seen cap this far along the axis from the centre signs it (nearer, the cap's pixels tell no end)."""
STALE_DEG = 30.0
"""A perceived axis this far or farther from the tracked top (either sign) means the object turned while no hand
held it and no settle watched it (knocked over): its top is read again before a hand takes it."""


def hand_rotation(arm_state: Any) -> np.ndarray:
    """The gripper frame from the arm's own encoders (extrinsic x-y-z degrees)."""
    return Rotation.from_euler("xyz", arm_state.tcp_rpy_deg, degrees=True).as_matrix()


def held_by(arm_state: Any) -> set[str]:
    return set(arm_state.held)


class Tops:
    """Signed axis (pointing to the object's top) per object in the world, and in the hand while held."""

    def __init__(self) -> None:
        self.world: dict[str, np.ndarray] = {}
        self.in_hand: dict[tuple[str, str], np.ndarray] = {}

    def observe(self, objects: Mapping[str, Any]) -> None:
        """Sign each perceived axis toward the seen cap (a container's opening), else like the current estimate;
        an object first seen standing has its top up."""
        for name, f in objects.items():
            if not getattr(f, "visible", False) or f.axis is None or f.upright is None:
                continue
            a = np.asarray(f.axis, dtype=float)
            a = a / max(float(np.linalg.norm(a)), 1e-12)
            ex = getattr(f, "extremes", None) or {}
            cap = ex.get("cap", ex.get("opening"))
            if cap is not None and f.centroid is not None:
                along = float((np.asarray(cap, dtype=float) - np.asarray(f.centroid, dtype=float)) @ a)
                if abs(along) >= CAP_ALONG_M:
                    self.world[name] = a if along > 0.0 else -a
                    continue
            ref = self.world.get(name)
            if ref is None:
                if f.upright:
                    self.world[name] = UP.copy()
                continue
            self.world[name] = a if float(a @ ref) >= 0.0 else -a

    def refresh(self, objects: Mapping[str, Any]) -> None:
        """Before a hand takes an object: read the top again (`observe`) of each object whose perceived axis no
        longer agrees with its tracked top. A bottle knocked over while both hands were busy elsewhere keeps the
        top it was first seen with (up); a top-down grasp of it then records its top along the approach axis, and
        the stand-up turns it no nearer upright. Objects whose axis still agrees keep their estimate."""
        stale = {}
        for name, f in objects.items():
            ref = self.world.get(name)
            if ref is None or not getattr(f, "visible", False) or f.axis is None:
                continue
            a = np.asarray(f.axis, dtype=float)
            cos = abs(float(a @ ref)) / max(float(np.linalg.norm(a) * np.linalg.norm(ref)), 1e-12)
            if cos < np.cos(np.radians(STALE_DEG)):
                stale[name] = f
        if stale:
            self.observe(stale)

    def before_grasp(self, call: Mapping[str, Any], perceive: Any) -> None:
        """Before an action: the objects its grasps take (a `drive`'s per-arm calls too) have their tops read
        again (`refresh`, from `perceive(names)`) so the hand records the top it really takes; objects a hand
        holds now are left to the encoders."""
        parts = [v for v in call.values() if isinstance(v, dict)] if call.get("action") == "drive" else [call]
        held = {o for (_, o) in self.in_hand}
        names = {p["obj"] for p in parts if p.get("action") == "grasp" and isinstance(p.get("obj"), str)} - held
        if names:
            self.refresh(perceive(names))

    def follow(self, arms: Mapping[str, Any]) -> None:
        """After an action: objects a hand holds turn with it; one that left a hand keeps the hand's last turn."""
        for arm, state in arms.items():
            rot, held = hand_rotation(state), held_by(state)
            for obj in held:
                key = (arm, obj)
                if key in self.in_hand:
                    self.world[obj] = rot @ self.in_hand[key]
                elif obj in self.world:
                    self.in_hand[key] = rot.T @ self.world[obj]
            for key in [k for k in self.in_hand if k[0] == arm and k[1] not in held]:
                self.world[key[1]] = rot @ self.in_hand.pop(key)

    def regrip(self, arm: str, obj: str, seen: Mapping[str, Any], arm_state: Any) -> None:
        """The hand closed on an object that had shifted in it (caught in the open fingers): its pose in the
        hand is read again from what is seen now, not carried over from the grasp it slipped from."""
        self.in_hand.pop((arm, obj), None)
        self.observe(seen)
        self.follow({arm: arm_state})

    def upright_turn(self, arm: str, arm_state: Any, shoulder: Any, swing_deg: float = 0.0) -> np.ndarray | None:
        """The world-frame turn of the hand that stands the object it holds up: its known top up, the hand level
        and facing away from the shoulder (an ordinary side grasp, which the arm reaches), swung `swing_deg`
        about the vertical from there. None when the hand holds nothing with a known top."""
        rot, held = hand_rotation(arm_state), held_by(arm_state)
        tops = [t for (a, o), t in self.in_hand.items() if a == arm and o in held]
        if not tops:
            return None
        hand = upright_hand(tops[0], arm_state.tcp_pos, shoulder, swing_deg)
        return None if hand is None else hand @ rot.T


def upright_hand(top_in_hand: Any, tcp_pos: Any, shoulder: Any, swing_deg: float = 0.0) -> np.ndarray | None:
    """The hand orientation (world frame) that holds an object with this top (in the hand's frame) top up, the
    hand level and facing away from the shoulder, swung `swing_deg` about the vertical; None when the top lies
    along the approach axis (no turn about a horizontal axis stands it up)."""
    approach = np.array([0.0, 0.0, 1.0])
    top = np.asarray(top_in_hand, dtype=float)
    top = top - float(top @ approach) * approach
    if np.linalg.norm(top) < 1e-6:
        return None
    top /= np.linalg.norm(top)
    out = np.asarray(tcp_pos, dtype=float)[:2] - np.asarray(shoulder, dtype=float)[:2]
    yaw = np.arctan2(out[1], out[0]) + np.radians(swing_deg)
    out = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    world = np.column_stack([UP, out, np.cross(UP, out)])
    hand = np.column_stack([top, approach, np.cross(top, approach)])
    return world @ hand.T


class Heads(Tops):
    """Signed axis pointing to each long lying object's head, kept the same way as the tops.

    The head is read once, at the first observation (`seed`: arms home, nothing on the object), as the axis
    end nearer the point cloud's centroid (the wide head pulls it). From then on its sign comes from the
    hand's encoders while held and from continuity while it lies or falls, never again from that rule: a hand
    over a utensil's middle hides the points it reads (a held spoon's perceived head flips end to end)."""

    def seed(self, objects: Mapping[str, Any]) -> None:
        for name, f in objects.items():
            if not getattr(f, "visible", False) or f.axis is None or f.upright is not False:
                continue
            yaw = head_yaw_deg(f)
            if yaw is not None:
                a = np.asarray(f.axis, dtype=float)
                a = a / max(float(np.linalg.norm(a)), 1e-12)
                head = np.array([np.cos(np.radians(yaw)), np.sin(np.radians(yaw)), 0.0])
                self.world[name] = a if float(a @ head) >= 0.0 else -a

    def observe(self, objects: Mapping[str, Any]) -> None:
        """Sign each seeded object's perceived axis like its current estimate (no new heads: see `seed`)."""
        super().observe({k: f for k, f in objects.items() if k in self.world})

    def yaw_deg(self, name: str) -> float | None:
        """The head's yaw about the vertical, degrees from +x; None when unknown."""
        h = self.world.get(name)
        if h is None or np.hypot(h[0], h[1]) < 1e-6:
            return None
        return float(np.degrees(np.arctan2(h[1], h[0])))
