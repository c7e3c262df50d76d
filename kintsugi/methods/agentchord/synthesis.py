"""Edge synthesis (Eq. 10) at run time: actions whose compiled arguments came from the first observation,
rewritten from what the robot perceives and knows now (a held object's tracked top or head, where a
re-grasped object is), just before the conductor sends them. No reasoning call; no task knowledge."""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.methods.agentchord.aim import region_call, relation_call
from kintsugi.methods.agentchord.keyframes import TabletopKeyframes
from kintsugi.methods.agentchord.observe import ARMS
from kintsugi.methods.agentchord.tops import Heads, Tops
from kintsugi.taskgraph.model import Edge, TaskGraph
from kintsugi.worlds.tabletop.clearance import across, gap

WHERE = (None, "centre")
"""The point features that say where an object is (its centroid, its centre)."""
GRASP_Z_MIN_M = 0.029
"""A top-down grasp point is no lower than this (the pads' half length plus the table clearance)."""
UPRIGHT_SWINGS_DEG = (0.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0)
"""Standing a held object up: the hand faces away from the shoulder, or swung this far about the vertical."""
FINGER_CLEAR_M = 0.01
"""A side grasp whose open fingers (on the way in, closed, and lifted as far as a lift goes) pass this close to
another perceived object is taken from another facing, the one that clears the neighbours most (pour-dual
seed 1: a bottle fallen upright against the held-up cup; one finger closed just under the cup and the lift
carried the cup up out of the other hand)."""
SIDE_SWINGS_DEG = (30.0, -30.0, 60.0, -60.0, 90.0, -90.0)
FINGER_HALF_OPEN_M = 0.05
FINGER_REACH_M = 0.025
"""The open fingers are this far either side of the grasp point, and reach this far past it along the approach."""
MOVED_M = 0.02
"""An object taken up this far from where it was first seen was taken up again elsewhere (after a fall)."""
PLACE_CLEAR_M = 0.05
"""...and is set down there only with this much room to every other object (the fingers and palm around it)."""
JOINT_MARGIN_DEG = 30.0
"""A turn that stands a held object up should leave every joint this far inside its limits: the place that
follows moves the base and turns the wrist's last roll with it (a roll left at its limit made the place's
retreat flip the wrist and knock the bottle it had just stood up over)."""



def region_centre(c: Any) -> tuple[float, float]:
    """The x-y centre of an `in_region` constraint's box."""
    return (c.lo[0] + c.hi[0]) / 2.0, (c.lo[1] + c.hi[1]) / 2.0


class EdgeSynthesis:
    def __init__(self, graph: TaskGraph, robot: Any, keyframes: TabletopKeyframes, tops: Tops, heads: Heads,
                 seen: dict[str, tuple[float, float]] | None = None) -> None:
        self.graph, self.robot, self.keyframes = graph, robot, keyframes
        self.seen = dict(seen or {})
        """Object -> (x, y) of its centroid in the observation the graph's arguments were filled from."""
        self.taken: dict[str, tuple[float, float]] = {}
        """Object -> (x, y) of its centroid where a hand last closed on it."""
        self.tops = tops
        """Which end of each object is its top (for standing a fallen object up the right way round)."""
        self.heads = heads
        """Which way each lying utensil's head points (for turning it to an absolute heading)."""
        self.missed: dict[tuple[str, str], int] = {}
        """(arm, object) -> grasps in a row that closed on nothing (see `grasp_outcome`)."""

    def adapt(self, edge: Edge, call: dict) -> dict:
        """The call to send for one of the edge's atomic actions."""
        name = call["action"]
        if name == "rotate_eef" and call.get("axis") == "closing" and self._wants_upright(edge):
            call = self.upright_call(call)
        if name == "drive":
            call = self._carry_call(edge, call)
        if name == "rotate_eef" and call.get("axis") == "approach":
            call = self._heading_call(edge, call)
        if name == "grasp" and call.get("yaw_deg") is None and call.get("grasp_offset") is None:
            stand = self._stand_grasp_call(edge, call)
            call = stand if stand is not None else self._grasp_call(call)
            if call.get("yaw_deg") is None:
                call = self._clear_grasp_call(call)
        if name == "place":
            target = self.graph.node(edge.target)
            placed = self._stand_place_call(edge, call) or self._place_call(call)
            call = region_call(target, self.robot, relation_call(target, self.robot, self.seen, placed))
        return call

    def _stand_place_call(self, edge: Edge, call: dict) -> dict | None:
        """Edge synthesis (Eq. 10) of the place that ends a stand-up (the edge turns its held object upright): the
        spot where the object was first seen, when that spot is clear of every other object by PLACE_CLEAR_M and
        the arm can carry it there (planned before anything moves); None (the place as given) otherwise. A knocked
        object rolls anywhere: stood up where it lay, it stood beside the robot's body, where the joint-space
        carry that followed swept it through the other arm, or in the way of the other arm's grasp. The spot it
        was first seen at is the one the plan's reach and carries were made for."""
        if not self._wants_upright(edge) or not any(a.name == "rotate_eef" and a.args.get("axis") == "closing"
                                                    for a in edge.actions):
            return None
        plan = getattr(self.robot, "execute", None)
        for obj in sorted(self.robot.arm_state(call["arm"]).held):
            first = self.seen.get(obj)
            moved = None if first is None else {**call, "x": round(first[0], 4), "y": round(first[1], 4)}
            if moved and self._clear(obj, first) and (plan is None or plan(moved, plan_only=True).planned):
                return moved
        return None

    def _place_call(self, call: dict) -> dict:
        """A place back where the held object was first seen, after the object was taken up again elsewhere (a
        re-grasp where it fell), goes where it was last taken up instead when that spot is clear of every other
        object by PLACE_CLEAR_M: it stood there a moment ago, and it is nearer (a re-planner, filling the place
        from the scene it sees then, does the same; pour-single seed 67 cost AgentChord 35 control steps more
        than code-as-monitor). A bottle dropped on the way to the cup often lies beside the cup: set down there,
        the hand knocked the cup over (seed 70)."""
        for obj in sorted(self.robot.arm_state(call["arm"]).held):
            first, last = self.seen.get(obj), self.taken.get(obj)
            if first is None or last is None:
                continue
            if (np.hypot(call["x"] - first[0], call["y"] - first[1]) < 1e-3
                    and np.hypot(last[0] - first[0], last[1] - first[1]) > MOVED_M and self._clear(obj, last)):
                return {**call, "x": round(last[0], 4), "y": round(last[1], 4)}
        return call

    def _clear(self, obj: str, spot: tuple[float, float]) -> bool:
        """Every other perceived object is PLACE_CLEAR_M beyond touching `obj` set down at `spot` (footprints as
        discs: half the middle of the perceived extents, an upright bottle's diameter rather than its height)."""
        feats = self.robot.features()

        def radius(name: str) -> float:
            ext = feats[name].extent
            return sorted(ext)[1] / 2.0 if ext else 0.0

        return all(np.hypot(spot[0] - f.centroid[0], spot[1] - f.centroid[1]) >= radius(obj) + radius(k) + PLACE_CLEAR_M
                   for k, f in feats.items() if k != obj and f.centroid is not None)

    def _wants_upright(self, edge: Edge) -> bool:
        return any(c.kind == "upright" for c in self.graph.node(edge.target).constraints)

    def upright_call(self, call: dict) -> dict:
        """Edge synthesis (Eq. 10) of a turn toward an upright sub-goal: the hand orientation that puts the held
        object's known top up, level and facing away from the shoulder; as given when nothing held has a top.
        Of the facings, the first whose whole turn the arm follows on its own branch (every waypoint's IK, no
        wrist flip) and that leaves its joints inside their limits; else the first whose end the arm reaches."""
        from scipy.spatial.transform import Rotation

        from kintsugi.methods.agentchord.tops import hand_rotation

        arm = call["arm"]
        state = self.robot.arm_state(arm)
        ik, pos, rot = self.keyframes.iks[arm], np.array(state.tcp_pos), hand_rotation(state)
        q = np.radians(state.joints_deg)
        turns = []
        for swing in UPRIGHT_SWINGS_DEG:
            turn = self.tops.upright_turn(arm, state, self.keyframes.shoulders[arm], swing)
            if turn is None:
                return call
            turns.append(turn)
        good = next((t for t in turns if self._turn_margin(arm, q, pos, rot, t @ rot) >= JOINT_MARGIN_DEG), None)
        if good is None:
            good = next((t for t in turns if ik.solve(pos, t @ rot, q).ok), turns[-1])
        rpy = Rotation.from_matrix(good).as_euler("xyz", degrees=True)
        return {"action": "move_by_offset", "arm": arm, "dxyz": (0.0, 0.0, 0.0), "frame": "world",
                "drpy_deg": tuple(round(float(v), 3) for v in rpy)}

    def _turn_margin(self, arm: str, q: np.ndarray, pos: np.ndarray, rot: np.ndarray, goal: np.ndarray) -> float:
        """How far inside its limits (degrees, the tightest joint) the arm ends a straight turn of the hand from
        `rot` to `goal` about `pos`, starting from joints `q`; -inf when it cannot follow it on its branch."""
        from kintsugi.core.errors import KintsugiError
        from kintsugi.worlds.tabletop.planning import BRANCH_JUMP_DEG, Planner

        ik = self.keyframes.iks[arm]
        try:
            move = Planner(self.keyframes.cfg, self.keyframes.iks, {})._linear(arm, (pos, rot), (pos, goal), q,
                                                                               "the turn", "turn")
        except KintsugiError:
            return float("-inf")
        path = np.vstack([q, *move.waypoints])
        if np.degrees(np.abs(np.diff(path, axis=0))).max() > BRANCH_JUMP_DEG:
            return float("-inf")
        end = path[-1]
        return float(np.degrees(np.minimum(end - ik.lower, ik.upper - end)).min())

    def _stand_grasp_call(self, edge: Edge, call: dict) -> dict | None:
        """Edge synthesis (Eq. 10) of the top-down grasp that begins standing a lying object up (the edge goes
        on to turn the hand toward an upright sub-goal): of the two hand yaws that close across it (a parallel
        gripper is the same either way round), the one from which the whole stand-up is best followed: grasp,
        lift, then the turn that brings the object's known top up (`upright_call`), with the most room left at
        the joints. The two end a half turn apart about the approach axis: one left the wrist's last roll at its
        limit. None (the default grasp) when the edge stands nothing up, the top is unknown, or after a miss."""
        from kintsugi.methods.agentchord.domain import UPEND_LIFT_M
        from kintsugi.methods.agentchord.tops import upright_hand
        from kintsugi.taskgraph.geometry import wrap_deg
        from kintsugi.worlds.tabletop.planning import down_rotation

        arm, obj = call["arm"], call["obj"]
        turns_up = any(a.name == "rotate_eef" and a.args.get("axis") == "closing" for a in edge.actions)
        if not turns_up or not self._wants_upright(edge) or self.missed.get((arm, obj), 0) % 2 == 1:
            return None
        top = self.tops.world.get(obj)
        seen = self.robot.features({obj})[obj]
        if top is None or not seen.visible or seen.centroid is None or seen.axis is None:
            return None
        if seen.tilt_deg is None or seen.tilt_deg < 45.0:
            return None
        ik, shoulder = self.keyframes.iks[arm], self.keyframes.shoulders[arm]
        state = self.robot.arm_state(arm)
        q0 = np.radians(state.joints_deg)
        c = np.array(seen.centroid, dtype=float)
        c[2] = max(c[2], GRASP_Z_MIN_M)
        base = np.asarray(self.robot.bases[arm], dtype=float) if hasattr(self.robot, "bases") else shoulder
        radial = np.degrees(np.arctan2(c[1] - base[1], c[0] - base[0]))
        along = np.degrees(np.arctan2(seen.axis[1], seen.axis[0]))
        yaw0 = radial + ((along - radial + 90.0) % 180.0 - 90.0)
        lifted = c + np.array([0.0, 0.0, UPEND_LIFT_M])
        best: tuple[tuple[int, float], float] | None = None
        for yaw in (yaw0, yaw0 + 180.0):
            rot = down_rotation(np.radians(yaw))
            above = ik.solve(c + np.array([0.0, 0.0, 0.1]), rot, q0)
            grasp = ik.solve(c, rot, above.q) if above.ok else above
            lift = ik.solve(lifted, rot, grasp.q) if grasp.ok else grasp
            if not lift.ok:
                continue
            score = None
            for i, swing in enumerate(UPRIGHT_SWINGS_DEG):
                goal = upright_hand(rot.T @ np.asarray(top, dtype=float), lifted, shoulder, swing)
                if goal is None:
                    return None
                m = self._turn_margin(arm, lift.q, lifted, rot, goal)
                if m >= JOINT_MARGIN_DEG:
                    score = (-i, m)
                    break
            if score is not None and (best is None or score > best[0]):
                best = (score, yaw)
        if best is None:
            return None
        return {**call, "yaw_deg": round(float(wrap_deg(best[1])), 3)}

    def _heading_call(self, edge: Edge, call: dict) -> dict:
        """Edge synthesis (Eq. 10) of a turn toward a `heading` sub-goal: the absolute turn about the vertical
        that brings the held object's tracked head (`Heads`) to the sub-goal's yaw. The compiled angle was
        relative to the first observation: wrong for an object re-grasped after it fell mid-turn."""
        from kintsugi.methods.agentchord.tops import hand_rotation, held_by
        from kintsugi.taskgraph.geometry import wrap_deg

        state = self.robot.arm_state(call["arm"])
        goal = next(((c.object, c.yaw_deg) for c in self.graph.node(edge.target).constraints
                     if c.kind == "heading" and c.object in held_by(state)), None)
        if goal is None or hand_rotation(state)[2, 2] > -0.9:  # a hand pointing down turns it about the vertical
            return call
        yaw = self.heads.yaw_deg(goal[0])
        if yaw is None:
            return call
        # A hand pointing down turns what it holds by minus its own turn about the approach axis (the move
        # slerps the short way, so this is the whole choice).
        return {**call, "angle_deg": round(wrap_deg(yaw - goal[1]), 3)}

    def _grasp_call(self, call: dict) -> dict:
        """Edge synthesis (Eq. 10) of a top-down grasp on a utensil that must end at a heading: of the two hand
        yaws that close across it, the one whose hand, once the utensil is turned to its heading, faces nearest
        the way the arm points at the region (the grasp's own default picks by where it lies now; a utensil
        fallen the other way round then needs a wrist turn the arm does not reach over the region). Kept only
        when the arm reaches that grasp (IK checked before moving)."""
        from scipy.spatial.transform import Rotation

        from kintsugi.taskgraph.geometry import wrap_deg

        arm, obj = call["arm"], call["obj"]
        misses = self.missed.get((arm, obj), 0)
        if misses % 2 == 1:  # the chosen yaw missed: the default next (and the chosen one again after that)
            return call
        psi, centre = self._heading_goal(obj), self._region_of(obj)
        head = self.heads.yaw_deg(obj)
        seen = self.robot.features({obj})[obj]
        if psi is None or centre is None or head is None or not seen.visible or seen.centroid is None:
            return call
        shoulder = np.asarray(self.keyframes.shoulders[arm], dtype=float)
        radial = np.degrees(np.arctan2(centre[1] - shoulder[1], centre[0] - shoulder[0]))
        final = min((psi, psi + 180.0), key=lambda y: abs(wrap_deg(y - radial)))
        yaw = wrap_deg(head + final - psi)
        c = np.array(seen.centroid, dtype=float)
        c[2] = max(c[2], GRASP_Z_MIN_M)
        rot = Rotation.from_euler("ZY", [np.radians(yaw), np.pi]).as_matrix()
        state = self.robot.arm_state(arm)
        if not self.keyframes.iks[arm].solve(c, rot, np.radians(state.joints_deg)).ok:
            return call
        return {**call, "yaw_deg": round(float(yaw), 3)}

    def _clear_grasp_call(self, call: dict) -> dict:
        """Edge synthesis (Eq. 10) of a side grasp on an upright object: as given when its fingers clear every other
        perceived object by FINGER_CLEAR_M, else the facing (swung about the vertical from the default, which
        faces away from the arm's base) whose fingers clear them most, among those the arm reaches (IK of the
        pre-grasp and grasp poses, checked before moving). Only perceived geometry is read."""
        from kintsugi.methods.agentchord.domain import LIFT_M, UPEND_LIFT_M
        from kintsugi.worlds.tabletop.planning import side_rotation

        arm, obj = call["arm"], call["obj"]
        if self.missed.get((arm, obj), 0) % 2 == 1:
            return call
        seen = self.robot.features()
        f = seen.get(obj)
        if f is None or not f.visible or f.centroid is None or not f.upright or f.axis is None:
            return call
        if not hasattr(self.robot, "bases"):
            return call
        others = [o for k, o in seen.items() if k != obj and o.visible and o.centroid is not None]
        if not others:
            return call
        c = np.array(f.centroid, dtype=float)
        radius = across(f)
        base = np.asarray(self.robot.bases[arm], dtype=float)
        radial = float(np.arctan2(c[1] - base[1], c[0] - base[0]))
        pre = float(call.get("pre_grasp_offset", 0.08))
        rise = max(LIFT_M, UPEND_LIFT_M)

        def clearance(yaw: float) -> float:
            rot = side_rotation(yaw)
            approach, closing = rot[:, 2], rot[:, 1]
            pts = [c + s * approach + w * closing for s in np.linspace(-pre, FINGER_REACH_M, 6)
                   for w in (-FINGER_HALF_OPEN_M, FINGER_HALF_OPEN_M)]
            pts += [c + s * approach + w * closing for s in (0.0, FINGER_REACH_M) for w in (-radius, radius)]
            return min(gap(p, c[2] - 0.015, c[2] + 0.015 + rise, o) for p in pts for o in others)

        if clearance(radial) >= FINGER_CLEAR_M:
            return call
        ik, q = self.keyframes.iks[arm], np.radians(self.robot.arm_state(arm).joints_deg)
        best, best_yaw = clearance(radial), None
        for swing in SIDE_SWINGS_DEG:
            yaw = radial + np.radians(swing)
            room = clearance(yaw)
            if room <= best + 1e-3:
                continue
            rot = side_rotation(yaw)
            first = ik.solve(c - pre * rot[:, 2], rot, q)
            if first.ok and ik.solve(c, rot, first.q).ok:
                best, best_yaw = room, yaw
        if best_yaw is None:
            return call
        return {**call, "yaw_deg": round(float(np.degrees(best_yaw) + 180.0) % 360.0 - 180.0, 3)}

    def grasp_outcome(self, call: dict) -> None:
        """Count grasps that closed on nothing in a row: the next one is tried the other way (chosen yaw <->
        default), so a recovery that re-runs it does not repeat the same miss."""
        key = (call["arm"], call["obj"])
        if call["obj"] in self.robot.grip_sense(call["arm"]).touching:
            self.missed.pop(key, None)
            f = self.robot.features({call["obj"]}).get(call["obj"])
            if f is not None and f.centroid is not None:
                self.taken[call["obj"]] = (float(f.centroid[0]), float(f.centroid[1]))
        else:
            self.missed[key] = self.missed.get(key, 0) + 1

    def _heading_goal(self, obj: str) -> float | None:
        return next((c.yaw_deg for n in self.graph.nodes for c in n.constraints
                     if c.kind == "heading" and c.object == obj), None)

    def _region_of(self, obj: str) -> tuple[float, float] | None:
        """The centre (x, y) of a region some sub-goal puts the object's centroid in."""
        for n in self.graph.nodes:
            for c in n.constraints:
                if (c.kind == "in_region" and c.point.entity == obj and c.point.feature in WHERE
                        and c.hi[0] - c.lo[0] < 1.0):
                    return region_centre(c)
        return None

    def _carry_call(self, edge: Edge, call: dict) -> dict:
        """Edge synthesis (Eq. 10) of a two-arm carry toward a region sub-goal: the same horizontal shift for
        both hands, from the held object's centroid perceived now to the region's centre. The compiled shift
        came from the first observation, and a recovery re-grasps the object wherever it fell."""
        inner = [call[a] for a in ARMS if isinstance(call.get(a), dict)]
        shifts = {tuple(i.get("dxyz", ())) for i in inner}
        if (len(inner) < 2 or any(i.get("action") != "move_by_offset" or i.get("frame", "world") != "world"
                                  for i in inner) or len(shifts) != 1):
            return call
        dxyz = next(iter(shifts))
        if len(dxyz) != 3 or abs(dxyz[0]) + abs(dxyz[1]) < 1e-9:
            return call
        goal = self._region_goal(edge, {a["arm"] for a in inner})
        if goal is None:
            return call
        obj, centre = goal
        seen = self.robot.features({obj})[obj]
        if not seen.visible or seen.centroid is None:
            return call
        shift = [round(float(centre[0] - seen.centroid[0]), 4), round(float(centre[1] - seen.centroid[1]), 4), dxyz[2]]
        return {**call, **{i["arm"]: {**i, "dxyz": shift} for i in inner}}

    def _region_goal(self, edge: Edge, arms: set[str]) -> tuple[str, tuple[float, float]] | None:
        """(object, region centre x-y) of an `in_region` constraint of the edge's target on the centroid of an
        object every one of `arms` holds now (both pads touching)."""
        held = None
        for arm in arms:
            now = set(self.robot.arm_state(arm).held)
            held = now if held is None else held & now
        for c in self.graph.node(edge.target).constraints:
            if c.kind != "in_region" or c.point.feature not in WHERE or c.point.along is not None:
                continue
            if c.point.entity in (held or set()):
                x, y = region_centre(c)
                if c.anchor is not None:  # the region rides with its anchor: where that is perceived now
                    f = self.robot.features({c.anchor}).get(c.anchor)
                    if f is not None and f.visible and f.centroid is not None:
                        x, y = x + f.centroid[0] - c.anchor_at[0], y + f.centroid[1] - c.anchor_at[1]
                return c.point.entity, (x, y)
        return None
