"""When the arm cannot reach what an action asks: other ways to do the same action, then a recorded failure.

An unreachable pose is a failed action, never a trial error. The conductor asks `alternatives` for other
calls that reach the same sub-goal from where the robot stands, tries them in order (each is planned before
anything moves, so a refusal costs no motion), and only when none is reachable raises `Unreachable`; the
conductor then ends the trial as a recorded failure with the reason, or re-plans when it may.

- a grasp of an object lying on the table (a knocked bottle rolled to the edge of reach): the grasp point slides
  along the object's principal axis towards the arm's base, as far as the object's perceived length allows
  (re-grasped where it lies, at the part of it the arm reaches);
- a grasp of a standing object: the side approach turns about the vertical (the default approach, away from
  the base, runs out of reach near the robot or far out);
- an object no arm of the plan grasps where it lies: pushed back into reach first (`Pushing`);
- a turn of a held object the arm cannot make where the hand is (standing a bottle up beside the body): the
  object is carried towards the middle of the arm's reach first;
- a place whose spot cannot be reached: the nearest clear spots around it, within the tolerance of the node it
  leads to when that node says where the object must be, else up to `FREE_PLACE_M` away.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from kintsugi.methods.agentchord.keyframes import KeyframeError
from kintsugi.perception.features import ObjectFeatures

LYING_TILT_DEG = 45.0
"""An object whose perceived axis is this far or more from vertical lies: its grasp point may slide along it."""
SLIDE_STEP_M = 0.02
END_MARGIN_M = 0.03
"""A slid grasp point stays this far from either end of the object's perceived length."""
NEAR_CENTRE_M = 0.04
"""A lying object is grasped this far off its centre at most for the action itself (standing it up from farther
along swings it wide); farther out, the grasp only drags it back into reach."""
PULL_GRASP_MARGIN_M = 0.012
PULL_PRE_GRASP_M = 0.04
PULL_M = 0.15
SHORT_PRE_GRASP_M = 0.04
COMFORT_M = 0.5
"""Distance from the arm's base (horizontal) a dragged object is brought towards."""
PULL_LIFT_M = 0.015
TURN_CARRIES = 2
DRAG_MAX_Z_M = 0.08
"""A hand this low holds its object on the table (a lying bottle just taken): it can slide it."""
PULL_PITCHES_DEG = (30.0, -30.0, 50.0, -50.0)
"""Hand tilts tried for the drag's grasp when no straight-down one reaches (leaning in from the arm's side)."""
YAW_TURNS_DEG = (30.0, -30.0, 60.0, -60.0, 90.0, -90.0)
PLACE_RINGS_M = (0.03, 0.06, 0.09, 0.12, 0.16, 0.20, 0.25, 0.30)
FREE_PLACE_M = 0.30
"""How far a place with no location in its sub-goal (standing a fallen bottle back up) may move its spot."""
LOCATED_PLACE_M = 0.02
"""How far a place into a region or container may move its spot (the region checks allow 4 cm)."""
CLEAR_M = 0.03


class Unreachable(KeyframeError):
    """No way of doing the action is within the arm's reach: the action failed (recorded, nothing moved)."""


def _unit_xy(v: Any) -> np.ndarray | None:
    a = np.array([float(v[0]), float(v[1])])
    n = float(np.linalg.norm(a))
    return None if n < 1e-6 else a / n


def lying(f: ObjectFeatures | None) -> bool:
    return bool(f is not None and f.centroid is not None and f.tilt_deg is not None and f.tilt_deg >= LYING_TILT_DEG
                and f.axis is not None and f.extent)


def slides(call: dict, f: ObjectFeatures, base: np.ndarray, margin: float, most: float | None = None) -> list[dict]:
    """Grasps of a lying object slid along its axis, towards the arm's base first, nearest the centre first."""
    x = _unit_xy(f.axis)
    if x is None:
        return []
    half = float(f.extent[0]) / 2.0 - margin
    if most is not None:
        half = min(half, most)
    to_base = np.asarray(base[:2], float) - np.asarray(f.centroid[:2], float)
    sign = 1.0 if float(x @ to_base) >= 0.0 else -1.0  # the object frame's x is along the axis
    out = []
    for s in (sign, -sign):
        for d in np.arange(SLIDE_STEP_M, half + 1e-9, SLIDE_STEP_M):
            out.append({**call, "grasp_offset": [round(s * float(d), 4), 0.0, 0.0]})
        if half > SLIDE_STEP_M and abs(half % SLIDE_STEP_M) > 1e-3:
            out.append({**call, "grasp_offset": [round(s * half, 4), 0.0, 0.0]})
    return out


def grasp_alternatives(call: dict, f: ObjectFeatures | None, base: np.ndarray) -> list[dict]:
    """Other grasps of the same object: a lying one a little off its centre, a standing one from another side."""
    if f is None or f.centroid is None:
        return []
    if lying(f):
        return slides(call, f, base, END_MARGIN_M, NEAR_CENTRE_M) if call.get("grasp_offset") is None else []
    if call.get("yaw_deg") is not None:
        return []
    c = np.asarray(f.centroid, float)
    radial = math.degrees(math.atan2(c[1] - base[1], c[0] - base[0]))
    out = [{**call, "yaw_deg": round((radial + turn + 180.0) % 360.0 - 180.0, 2)} for turn in YAW_TURNS_DEG]
    if float(call.get("pre_grasp_offset", 0.08)) > SHORT_PRE_GRASP_M:  # close to the base, a long approach
        short = {**call, "pre_grasp_offset": SHORT_PRE_GRASP_M}  # backs the hand out of the workspace
        out += [short] + [{**a, "pre_grasp_offset": SHORT_PRE_GRASP_M} for a in out]
    return out


def pull_vector(f: ObjectFeatures, base: np.ndarray) -> np.ndarray:
    """Where to drag a lying object out of the edge of reach: along the line from the arm's base, towards the
    middle of its reach (towards the base from far out, away from it from too close)."""
    c = np.asarray(f.centroid[:2], float)
    d = c - np.asarray(base[:2], float)
    dist = float(np.linalg.norm(d))
    u = d / max(dist, 1e-6)
    return u * float(np.clip(COMFORT_M - dist, -PULL_M, PULL_M))


def footprint(f: ObjectFeatures | None) -> float:
    """Half the object's horizontal size: across its axis when it stands, along it when it lies."""
    if f is None or not f.extent:
        return 0.0
    if f.tilt_deg is not None and f.tilt_deg < LYING_TILT_DEG and len(f.extent) > 1:
        return max(f.extent[1:]) / 2.0
    return max(f.extent) / 2.0


def place_alternatives(call: dict, others: list[ObjectFeatures], held: ObjectFeatures | None,
                       located: bool) -> list[dict]:
    """The nearest clear spots around an unreachable place's spot (tighter when the sub-goal locates it)."""
    reach = LOCATED_PLACE_M if located else FREE_PLACE_M
    c = np.array([float(call["x"]), float(call["y"])])
    half = footprint(held)
    out: list[dict] = []
    rings = [r for r in PLACE_RINGS_M if r <= reach + 1e-9] or [reach]
    for r in rings:
        for a in np.linspace(0.0, 2.0 * math.pi, 12, endpoint=False):
            p = c + r * np.array([math.cos(a), math.sin(a)])
            if all(o.centroid is None or np.linalg.norm(p - np.asarray(o.centroid[:2], float))
                   >= half + footprint(o) + CLEAR_M for o in others):
                out.append({**call, "x": round(float(p[0]), 4), "y": round(float(p[1]), 4)})
    return out


def locates(node: Any, obj: str | None) -> bool:
    """The node's constraints say where `obj` must be (a region, a container)."""
    if obj is None:
        return False
    for c in node.constraints:
        if not any(e == obj for e, role, _ in c.refs() if role != "arm"):
            continue
        if c.kind in ("within", "inside"):
            return True
        if c.kind == "in_region" and min(h - lo for lo, h in zip(c.lo[:2], c.hi[:2])) < 1.0:
            return True  # a region of the table (on_table's box spans the whole table)
    return False


class Reaching:
    """The conductor's way round an unreachable action (a mixin of `Conductor`: it reads through its robot)."""

    robot: Any
    log: Any
    graph: Any

    def reach_otherwise(self, edge: Any, call: dict, result: Any) -> tuple[Any, dict]:
        """The first alternative to `call` the arm can carry out, run: (its result, its call); or the refused
        result and call when none can (nothing moved)."""
        name, arm = call.get("action"), call.get("arm")
        if arm not in ("left", "right"):
            return result, call
        f = None
        if name == "grasp" and isinstance(call.get("obj"), str):
            f = self.robot.features({call["obj"]}).get(call["obj"])
            options = grasp_alternatives(call, f, np.asarray(self.robot.bases[arm], float))
        elif name == "place":
            seen = self.robot.features()
            held = sorted(self.robot.arm_state(arm).held)
            others = [v for k, v in seen.items() if k not in held]
            options = place_alternatives(call, others, seen.get(held[0]) if held else None,
                                         any(locates(self.graph.node(edge.target), k) for k in held))
        else:
            options = []
            if name == "move_by_offset" and self.drag_held(edge, call):
                if self.feasible(call):
                    return self.robot.execute(call), call
            turned = self.carry_to_turn(edge, call) if name in ("rotate_eef", "move_by_offset") else None
            if turned is not None:
                return self.robot.execute(turned), turned
        for alt in options:
            if self.feasible(alt):
                tried = self.robot.execute(alt)
                changed = {k: v for k, v in alt.items() if call.get(k) != v}
                self.log.event(self.robot.sim_time, "reached otherwise", f"{edge.id} {name}: {result.message}; "
                               f"carried out with {changed}")
                return tried, alt
        if name == "grasp" and lying(f) and self.pull_into_reach(edge, call, f):
            f = self.robot.features({call["obj"]}).get(call["obj"])
            for alt in [call, *grasp_alternatives(call, f, np.asarray(self.robot.bases[arm], float))]:
                if self.feasible(alt):
                    return self.robot.execute(alt), alt
        if name == "grasp" and f is not None and f.centroid is not None and not any(
                self.grasp_reachable(call, a) for a in sorted(self.arms) if a in ("left", "right") and a != arm):
            if self.push_into_reach(edge, call):  # no arm grasps it where it lies: pushed back into reach
                alt = self.grasp_reachable(call, arm)
                if alt is not None:
                    return self.robot.execute(alt), alt
        if options:
            self.log.event(self.robot.sim_time, "unreachable", f"{edge.id} {name}: none of {len(options)} other "
                           f"ways is within reach either")
        return result, call

    def feasible(self, call: dict) -> bool:
        """The arm can carry the call out as asked: planned, no target clipped to the workspace (nothing moves)."""
        try:
            r = self.robot.execute(call, plan_only=True)
        except TypeError:  # a robot without a planning-only mode: try it for real
            return True
        return bool(r.planned and not r.clipped)

    def drag_held(self, edge: Any, call: dict) -> bool:
        """A held object still on the table (taken where it lay at the edge of reach) that cannot be raised from
        there: slide it along the table towards the middle of the arm's reach first. True when it was slid."""
        state = self.robot.arm_state(call["arm"])
        tcp = np.asarray(state.tcp_pos, float)
        if not state.held or tcp[2] > DRAG_MAX_Z_M:
            return False
        base = np.asarray(self.robot.bases[call["arm"]], float)
        d = tcp[:2] - base[:2]
        dist = float(np.linalg.norm(d))
        move = d / max(dist, 1e-6) * float(np.clip(COMFORT_M - dist, -PULL_M, PULL_M))
        slide = {"action": "move_by_offset", "arm": call["arm"], "dxyz": [float(move[0]), float(move[1]), 0.0]}
        if float(np.linalg.norm(move)) < SLIDE_STEP_M or not self.feasible(slide):
            return False
        self.log.event(self.robot.sim_time, "pull into reach", f"{edge.id}: the held object cannot be raised where it "
                       f"lies; slid {np.round(move, 3).tolist()} m along the table first")
        self._execute(edge, "move_by_offset", {k: v for k, v in slide.items() if k != "action"}, unplanned_ok=True)
        return True

    def carry_to_turn(self, edge: Any, call: dict) -> dict | None:
        """A turn of a held, raised object the arm cannot make where the hand is (a stand-up beside the robot's
        body): carry it at its height towards the point straight ahead of the arm's base at `COMFORT_M`, up to
        `TURN_CARRIES` legs of `PULL_M`, until the turn can be made there. The turn to make then (synthesized
        again where the hand now is: an upright turn faces away from the shoulder), or None."""
        arm = call["arm"]
        state = self.robot.arm_state(arm)
        tcp = np.asarray(state.tcp_pos, float)
        turn = call.get("action") == "rotate_eef" or (call.get("drpy_deg") is not None
                                                       and not any(abs(float(v)) > 1e-9 for v in call.get("dxyz", ())))
        if not turn or not state.held or tcp[2] <= DRAG_MAX_Z_M:
            return None
        base = np.asarray(self.robot.bases[arm], float)
        own = next((a for a in edge.actions if a.name == "rotate_eef" and a.args.get("arm") == arm), None)
        for _ in range(TURN_CARRIES):
            tcp = np.asarray(self.robot.arm_state(arm).tcp_pos, float)
            d = base[:2] + np.array([COMFORT_M, 0.0]) - tcp[:2]
            move = d * min(1.0, PULL_M / max(float(np.linalg.norm(d)), 1e-6))
            carry = {"action": "move_by_offset", "arm": arm, "dxyz": [float(move[0]), float(move[1]), 0.0]}
            if float(np.linalg.norm(move)) < SLIDE_STEP_M or not self.feasible(carry):
                return None
            self.log.event(self.robot.sim_time, "carried to turn", f"{edge.id}: the turn is out of reach where the "
                           f"hand is; carried the held object {np.round(move, 3).tolist()} m first")
            self._execute(edge, "move_by_offset", {k: v for k, v in carry.items() if k != "action"}, unplanned_ok=True)
            again = call if own is None else self.synthesis.adapt(edge, {"action": "rotate_eef", **own.args})
            if self.feasible(again):
                return again
        return None

    def pull_into_reach(self, edge: Any, call: dict, f: ObjectFeatures) -> bool:
        """Drag a lying object the arm cannot grasp for the action back into reach: take it by the part of it
        the arm reaches, slide it along the table, let go and rise. True when it was dragged."""
        arm = call["arm"]
        base = np.asarray(self.robot.bases[arm], float)
        move = pull_vector(f, base)
        if float(np.linalg.norm(move)) < SLIDE_STEP_M:
            return False
        grip = {"action": "grasp", "arm": arm, "obj": call["obj"], "pre_grasp_offset": PULL_PRE_GRASP_M}
        takes = [grip] + slides(grip, f, base, PULL_GRASP_MARGIN_M)
        for alt in takes + [{**t, "pitch_deg": p} for p in PULL_PITCHES_DEG for t in takes]:
            if not self.feasible(alt):
                continue
            self._execute(edge, "grasp", {k: v for k, v in alt.items() if k != "action"}, unplanned_ok=True)
            self.log.event(self.robot.sim_time, "pull into reach", f"{call['obj']} lies out of the {arm} arm's reach "
                           f"for {edge.id}: dragged {np.round(move, 3).tolist()} m")
            steps = [("move_by_offset", {"dxyz": [0.0, 0.0, PULL_LIFT_M]}),
                     ("move_by_offset", {"dxyz": [float(move[0]), float(move[1]), 0.0]}),
                     ("move_by_offset", {"dxyz": [0.0, 0.0, -PULL_LIFT_M]}),
                     ("open_gripper", {}), ("move_by_offset", {"dxyz": [0.0, 0.0, 0.06]})]
            for action, args in steps:
                self._execute(edge, action, {"arm": arm, **args}, unplanned_ok=True)
            return True
        return False
