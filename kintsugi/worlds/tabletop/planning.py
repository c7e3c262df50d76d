"""Atomic action -> per-arm motion program, with every IK target solved before anything moves.

Targets come from what the robot perceives (object features) and its own commanded
pose. Straight-line segments (grasp approach, lift, lowering, retreat, rotations) are
split into short Cartesian steps, each an IK solution seeded by the previous one;
`move_to_obj`, `move_to_target` and `back` interpolate in joint space, as the paper does.
An unreachable target makes the whole action fail with `PlanError` (ik_failed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from kintsugi.perception.features import ObjectFeatures
from kintsugi.worlds.tabletop import actions as A
from kintsugi.worlds.tabletop.actions import PlanError
from kintsugi.worlds.tabletop.arm_model import PAD_HALF
from kintsugi.worlds.tabletop.clearance import gap, top_z
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.ik import ArmIK
from kintsugi.worlds.tabletop.motion import Grip, Move, Step
from kintsugi.worlds.tabletop.objects import Shape
from kintsugi.worlds.tabletop.pushing import push_program

LINEAR_STEP_M = 0.015
LINEAR_STEP_RAD = math.radians(10.0)
TABLE_CLEARANCE_M = 0.004
"""Finger tips stay this far above the table when grasping low objects."""
HOVER_CLEARANCE_M = 0.04
"""The fingers pass this far above an object's top on their way to its pre-grasp pose."""
FLAT_TILT_DEG = 45.0
PROPPED_DEG = 10.0
"""A lying object whose axis rises this much or more is taken square to its axis (`square_to`); below it, a
hand straight down fits (a utensil, a bottle lying on the table)."""
ACROSS_MAX = 0.2
"""|cos| of the angle between the closing axis and the object's axis up to which the hand closes across it."""
BRANCH_JUMP_DEG = 45.0
"""Between two waypoints of a straight line (at most LINEAR_STEP_M / LINEAR_STEP_RAD apart) no joint turns
this far unless the IK solution left the arm's branch (a wrist flip: the seeded solve met a joint limit and
the one from home won). The joint-space move between such waypoints is no straight line: it swings the hand
through a half turn."""

SWEEP_CLEAR_M = 0.015
"""A joint-space move to a grasp's hover pose keeps the open hand this far from every perceived object, or the
hand first rises straight up over them (and, if that is not enough, goes home). After a drop the empty hand is
often right beside what fell or what the other hand holds up, and a joint-space move from there swept the open
fingers through it (pour-dual: the held cup knocked out of the left hand)."""
SWEEP_SAMPLES = 24
RISE_MAX_M = 0.25
RISE_STEP_M = 0.05
"""Clearing the way for a joint-space move: rise in steps of this much until the move passes."""
HAND_HALF_OPEN_M = 0.05
PALM_BACK_M = 0.035
"""The open hand, as points about the tool centre: the pads' tips and roots either side, and the palm behind."""

AXES = {"normal": 0, "closing": 1, "approach": 2}


@dataclass(frozen=True)
class InHand:
    """An object as the hand took it: its bottom and centre relative to the tool, in the tool's frame, from the
    perceived features the grasp was planned from. A place reads them when the held object is hidden in the
    hand (a small capsule between the fingers shows the cameras a few points): the hand knows how it took it."""

    obj: str
    bottom: np.ndarray
    centre: np.ndarray


@dataclass
class ArmView:
    """What planning knows about one arm: its commanded joints and their tool pose, touch, and how the hand took
    what it holds (`InHand`, when its last action was the grasp of it or a move since)."""

    q: np.ndarray
    pos: np.ndarray
    rot: np.ndarray
    base: np.ndarray
    touching: dict[str, int]
    in_hand: InHand | None = None


def side_rotation(yaw: float) -> np.ndarray:
    """Gripper horizontal, approaching along `yaw`, fingers closing horizontally (a side grasp)."""
    return Rotation.from_euler("ZY", [yaw, math.pi / 2]).as_matrix()


def down_rotation(yaw: float) -> np.ndarray:
    """Gripper pointing down; its closing axis is horizontal, perpendicular to direction `yaw`."""
    return Rotation.from_euler("ZY", [yaw, math.pi]).as_matrix()


def square_to(rot: np.ndarray, f: ObjectFeatures) -> np.ndarray:
    """A top-down hand pitched about its closing axis until it approaches square to the object's axis, when
    the object lies propped up (its axis PROPPED_DEG or more above the horizontal, e.g. a bottle leaning on a
    cup) and the hand closes across that axis. Straight down, the palm met the raised end of a bottle leaning
    30 degrees before the pads reached it, and the pads closed on nothing (pour-single seed 86, ten times)."""
    if f.axis is None or f.tilt_deg is None or not PROPPED_DEG <= 90.0 - f.tilt_deg < 90.0 - FLAT_TILT_DEG:
        return rot
    a = np.asarray(f.axis, dtype=float) / max(float(np.linalg.norm(f.axis)), 1e-12)
    if abs(float(rot[:, 1] @ a)) > ACROSS_MAX:
        return rot
    pitch = _wrap_half_turn(math.atan2(-float(rot[:, 2] @ a), float(rot[:, 0] @ a)))
    return rot @ Rotation.from_euler("y", pitch).as_matrix()


def rpy_matrix(rpy_deg: tuple[float, float, float]) -> np.ndarray:
    return Rotation.from_euler("xyz", rpy_deg, degrees=True).as_matrix()


def _wrap_half_turn(a: float) -> float:
    """Angle modulo pi into [-pi/2, pi/2) (a parallel gripper is symmetric under a half turn)."""
    return (a + math.pi / 2) % math.pi - math.pi / 2


class Planner:
    def __init__(self, cfg: TabletopConfig, iks: dict[str, ArmIK], shapes: dict[str, Shape]) -> None:
        self.cfg = cfg
        self.iks = iks
        self.shapes = shapes
        self.clipped = False
        self.grasped: dict[str, InHand] = {}
        """Per arm, how its last planned grasp takes its object (the robot keeps it once the grasp has run)."""

    # --- IK helpers -----------------------------------------------------------
    def _solve(self, arm: str, pos: np.ndarray, rot: np.ndarray, seed: np.ndarray, what: str) -> np.ndarray:
        r = self.iks[arm].solve(pos, rot, seed)
        self.clipped |= r.clipped
        if not r.ok:
            raise PlanError(f"{arm} arm cannot reach {what} at ({', '.join(f'{v:.3f}' for v in pos)}): "
                            f"{r.message()}", ik_failed=True, clipped=r.clipped)
        return r.q

    def _linear(self, arm: str, start: tuple[np.ndarray, np.ndarray], goal: tuple[np.ndarray, np.ndarray],
                seed: np.ndarray, what: str, label: str) -> Move:
        """A straight-line move with slerped orientation, as IK waypoints."""
        p0, p1, r1, angle, dist, n, slerp = _line(start, goal)
        qs, q = [], seed
        for i in range(1, n + 1):
            s = i / n
            q = self._solve(arm, p0 + s * (p1 - p0), slerp(s).as_matrix(), q, what)
            qs.append(q)
        m = self.cfg.motion
        duration = max(dist / m.linear_speed_m_s, math.degrees(angle) / m.rotate_speed_deg_s)
        return Move(qs, min_duration_s=duration, tcp=(p1, r1), label=label)

    def _linear_prefix(self, arm: str, start: tuple[np.ndarray, np.ndarray], goal: tuple[np.ndarray, np.ndarray],
                       seed: np.ndarray, label: str) -> Move | None:
        """As much of a straight line as the arm follows on its own branch: the waypoints up to the first one
        that is unreachable or leaves the branch (BRANCH_JUMP_DEG); None when not even the first is. For moves
        that may stop short (backing an open hand away) and must never swing it."""
        p0, p1, r1, angle, dist, n, slerp = _line(start, goal)
        qs, q, s = [], seed, 0.0
        for i in range(1, n + 1):
            r = self.iks[arm].solve(p0 + i / n * (p1 - p0), slerp(i / n).as_matrix(), q)
            if not r.ok or r.clipped or np.degrees(np.abs(r.q - q)).max() > BRANCH_JUMP_DEG:
                break
            q, s = r.q, i / n
            qs.append(q)
        if not qs:
            return None
        m = self.cfg.motion
        duration = max(s * dist / m.linear_speed_m_s, s * math.degrees(angle) / m.rotate_speed_deg_s)
        return Move(qs, min_duration_s=duration, tcp=(p0 + s * (p1 - p0), slerp(s).as_matrix()), label=label)

    def _joint(self, arm: str, pos: np.ndarray, rot: np.ndarray, seed: np.ndarray, what: str, label: str) -> Move:
        return Move([self._solve(arm, pos, rot, seed, what)], tcp=(pos, rot), label=label)

    # --- object frames ----------------------------------------------------------
    @staticmethod
    def _visible(obj: str, f: ObjectFeatures | None) -> ObjectFeatures:
        if f is None or not f.visible or f.centroid is None:
            note = f" ({f.note})" if f is not None and f.note else ""
            raise PlanError(f"{obj} is not visible to the cameras{note}", unseen=True)
        return f

    @staticmethod
    def centre(f: ObjectFeatures) -> np.ndarray:
        """Where to hold and place an object: its fitted centre, or for a shape no primitive fits
        (a fork) the midpoint of its two axis ends, which a hand over its middle does not hide
        (the visible points' mean drifts by centimetres towards the wide head and away from the hand)."""
        ends = [f.extremes.get(k) for k in ("axis_pos", "axis_neg")]
        if f.fit == "raw" and all(e is not None for e in ends):
            mid = (np.array(ends[0]) + np.array(ends[1])) / 2
            return np.array([mid[0], mid[1], f.centroid[2]])
        return np.array(f.centroid)

    @staticmethod
    def object_frame(f: ObjectFeatures) -> np.ndarray:
        """z up; x along the principal axis when it lies flat (a fork, a fallen bottle), else world x."""
        axis = np.array(f.axis if f.axis is not None else (1.0, 0.0, 0.0))
        flat = f.tilt_deg is not None and f.tilt_deg > FLAT_TILT_DEG and np.hypot(axis[0], axis[1]) > 1e-6
        x = np.array([axis[0], axis[1], 0.0]) / np.hypot(axis[0], axis[1]) if flat else np.array([1.0, 0.0, 0.0])
        z = np.array([0.0, 0.0, 1.0])
        return np.column_stack([x, np.cross(z, x), z])

    # --- actions ---------------------------------------------------------------
    def plan(self, action: object, arm: ArmView, feats: dict[str, ObjectFeatures] | None) -> list[Step]:
        """Program for one single-arm action. `feats` is None when the action needs no perception."""
        name = action.action  # type: ignore[attr-defined]
        return getattr(self, f"_{name}")(action, arm, feats or {})

    def _open_gripper(self, a: A.OpenGripper, arm: ArmView, feats: dict) -> list[Step]:
        return [Grip(False, "open")]

    def _close_gripper(self, a: A.CloseGripper, arm: ArmView, feats: dict) -> list[Step]:
        return [Grip(True, "close", ramp_s=a.close_s)]

    def _back(self, a: A.Back, arm: ArmView, feats: dict) -> list[Step]:
        steps: list[Step] = []
        if a.rise_m > 0.0:
            out = self._linear_prefix(a.arm, (arm.pos, arm.rot), (arm.pos + np.array([0.0, 0.0, a.rise_m]), arm.rot),
                                      arm.q, "rise")
            if out is not None:
                steps.append(out)
        return steps + [self._home(a.arm)]

    def _move_to_target(self, a: A.MoveToTarget, arm: ArmView, feats: dict) -> list[Step]:
        rot = rpy_matrix(a.rpy_deg) if a.rpy_deg is not None else arm.rot
        return [self._joint(a.arm, np.array(a.xyz), rot, arm.q, "the target", "to target")]

    def _move_to_obj(self, a: A.MoveToObj, arm: ArmView, feats: dict) -> list[Step]:
        f = self._visible(a.obj, feats.get(a.obj))
        pos = np.array(f.centroid) + self.object_frame(f) @ np.array(a.offset)
        rot = rpy_matrix(a.rpy_deg) if a.rpy_deg is not None else arm.rot
        return [self._joint(a.arm, pos, rot, arm.q, f"the pose at {a.obj}", f"to {a.obj}")]

    def _move_by_offset(self, a: A.MoveByOffset, arm: ArmView, feats: dict) -> list[Step]:
        turn = rpy_matrix(a.drpy_deg)
        if a.frame == "world":
            pos, rot = arm.pos + np.array(a.dxyz), turn @ arm.rot
        else:
            pos, rot = arm.pos + arm.rot @ np.array(a.dxyz), arm.rot @ turn
        return [self._linear(a.arm, (arm.pos, arm.rot), (pos, rot), arm.q, "the offset pose", "offset")]

    def _rotate_eef(self, a: A.RotateEef, arm: ArmView, feats: dict) -> list[Step]:
        axis = np.zeros(3)
        axis[AXES[a.axis]] = 1.0
        rot = arm.rot @ Rotation.from_rotvec(math.radians(a.angle_deg) * axis).as_matrix()
        return [self._linear(a.arm, (arm.pos, arm.rot), (arm.pos, rot), arm.q, "the rotated pose", "rotate")]

    def _grasp(self, a: A.Grasp, arm: ArmView, feats: dict) -> list[Step]:
        f = self._visible(a.obj, feats.get(a.obj))
        shape = self.shapes[a.obj]
        c = self.centre(f)
        if a.grasp_offset is not None:
            c = c + self.object_frame(f) @ np.array(a.grasp_offset)
        radial = math.atan2(c[1] - arm.base[1], c[0] - arm.base[0])
        if a.yaw_deg is not None:
            radial = math.radians(a.yaw_deg)
        if shape.grasp == "side_if_upright" and f.upright:
            rot = side_rotation(radial)
            c[2] = max(c[2], PAD_HALF[0] + TABLE_CLEARANCE_M)
            style = "side-on (upright)"
        else:
            yaw = radial
            if f.tilt_deg is not None and f.axis is not None and f.tilt_deg > FLAT_TILT_DEG and a.yaw_deg is None:
                along = math.atan2(f.axis[1], f.axis[0])  # close across the principal axis
                yaw = radial + _wrap_half_turn(along - radial)
            rot = square_to(down_rotation(yaw), f)
            if a.pitch_deg:
                rot = rot @ Rotation.from_euler("y", a.pitch_deg, degrees=True).as_matrix()
            c[2] = max(c[2], PAD_HALF[2] + TABLE_CLEARANCE_M)
            style = "top-down" + (" (fallen)" if shape.grasp == "side_if_upright" else "")
        approach = rot[:, 2]
        self.grasped[a.arm] = InHand(a.obj, rot.T @ (np.array(f.extremes["bottom"]) - c), rot.T @ (self.centre(f) - c))
        pre = c - a.pre_grasp_offset * approach
        # Come down onto the pre-grasp pose from above the object, so the joint-space move
        # there never sweeps the fingers through it.
        below = PAD_HALF[0] if "side" in style else PAD_HALF[2]
        hover = pre.copy()
        hover[2] = max(pre[2], f.extremes["top"][2] + below + HOVER_CLEARANCE_M)
        try:
            q_hover = self._solve(a.arm, hover, rot, arm.q, f"the pose above {a.obj}")
        except PlanError:
            if hover[2] <= pre[2] + 1e-3:
                raise
            # Far out, a hand pointing down reaches lower before higher (a fallen bottle at the edge of reach):
            # come to the pre-grasp pose itself, already above the object by the pre-grasp offset.
            hover = pre.copy()
            q_hover = self._solve(a.arm, hover, rot, arm.q, f"the pre-grasp pose of {a.obj}")
        steps: list[Step] = [Grip(False, "open"), *self._way_clear(a.arm, arm, q_hover, feats),
                             Move([q_hover], tcp=(hover, rot), label=f"above {a.obj} {style}")]
        q_pre = q_hover
        if hover[2] > pre[2] + 1e-3:
            down = self._linear(a.arm, (hover, rot), (pre, rot), q_hover, f"the pre-grasp pose of {a.obj}",
                                f"pre-grasp {a.obj}")
            steps.append(down)
            q_pre = down.waypoints[-1]
        return steps + [
            self._linear(a.arm, (pre, rot), (c, rot), q_pre, f"the grasp pose of {a.obj}", f"approach {a.obj}"),
            Grip(True, "close", ramp_s=a.close_s),
        ]

    def _push(self, a: A.Push, arm: ArmView, feats: dict) -> list[Step]:
        return push_program(self, a, arm, feats)

    def _sweep_gap(self, arm: str, q0: np.ndarray, q1: np.ndarray, objs: list[ObjectFeatures]) -> float:
        """The least clearance of the open hand to the objects along the joint-space line from q0 to q1."""
        least = float("inf")
        for s in np.linspace(0.0, 1.0, SWEEP_SAMPLES):
            pos, rot = self.iks[arm].fk(q0 + s * (q1 - q0))
            closing, approach = rot[:, 1], rot[:, 2]
            pts = [pos + w * closing + t * approach for w in (-HAND_HALF_OPEN_M, HAND_HALF_OPEN_M)
                   for t in (-PAD_HALF[2], PAD_HALF[2])] + [pos - PALM_BACK_M * approach]
            least = min(least, *(gap(p, p[2] - PAD_HALF[0], p[2] + PAD_HALF[0], o) for p in pts for o in objs))
        return least

    def _way_clear(self, arm: str, view: ArmView, q_goal: np.ndarray, feats: dict) -> list[Step]:
        """Steps that clear the way for a joint-space move to q_goal: none when it passes every perceived object
        by SWEEP_CLEAR_M; else a straight rise over the tallest of them, or RISE_STEP_M steps higher, the least from
        which that move passes, and home as well when none does up to RISE_MAX_M. A hand that turns from side-on
        to pointing down right over the object it lost (handover seed 25: the block fell 10 cm from the placing
        hand) passes after a 10 cm rise: 0.36 s sooner than going home to turn."""
        objs = [o for o in feats.values() if o.visible and o.centroid is not None]
        if not objs or self._sweep_gap(arm, view.q, q_goal, objs) >= SWEEP_CLEAR_M:
            return []
        over = min(max(top_z(o) for o in objs) + HOVER_CLEARANCE_M + PAD_HALF[2] - view.pos[2], RISE_MAX_M)
        first = None  # the rise over the tallest object: taken on the way home when no rise lets the move pass
        for up in np.arange(over if over > 0.0 else RISE_STEP_M, RISE_MAX_M + 1e-9, RISE_STEP_M):
            rise = self._linear_prefix(arm, (view.pos, view.rot), (view.pos + np.array([0.0, 0.0, up]), view.rot),
                                       view.q, "rise clear")
            if rise is None:
                break
            first = first or rise
            if self._sweep_gap(arm, rise.waypoints[-1], q_goal, objs) >= SWEEP_CLEAR_M:
                return [rise]
            if rise.tcp[0][2] < view.pos[2] + up - 1e-3:  # the line stopped short: higher is out of reach
                break
        return ([first] if first is not None and over > 0.0 else []) + [self._home(arm)]

    def _home(self, arm: str) -> Move:
        home = self.iks[arm].home
        return Move([home.copy()], tcp=self.iks[arm].fk(home), label="home")

    def _place(self, a: A.Place, arm: ArmView, feats: dict) -> list[Step]:
        held = [k for k, n in arm.touching.items() if n == 2]
        table_z = 0.0
        took = arm.in_hand if arm.in_hand is not None and held and arm.in_hand.obj == held[0] else None
        if held and took is not None and not _seen(feats.get(held[0])):  # hidden in the hand: as it was taken
            below = -float((arm.rot @ took.bottom)[2])
            shift = -(arm.rot @ took.centre)[:2]
        elif held:
            f = self._visible(held[0], feats.get(held[0]))
            below = arm.pos[2] - f.extremes["bottom"][2]  # tool centre point above the object's bottom
            shift = arm.pos[:2] - self.centre(f)[:2]
        else:
            below = PAD_HALF[2]
            shift = np.zeros(2)
        rot = arm.rot
        low = np.array([a.x + shift[0], a.y + shift[1], table_z + below + a.z_offset + 0.003])
        over = low.copy()
        over[2] = max(arm.pos[2], low[2] + 0.05)
        q_over = self._solve(a.arm, over, rot, arm.q, "the pose over the place")
        lower = self._linear(a.arm, (over, rot), (low, rot), q_over, "the place pose", "lower")
        retreat_pos = low - self.cfg.motion.retreat_m * rot[:, 2]
        # Back away only as far as the line holds on the arm's branch: a wrist flip on the way swings the open
        # fingers through the object just set down (the released hand may stop short; it is open and empty).
        retreat = self._linear_prefix(a.arm, (low, rot), (retreat_pos, rot), lower.waypoints[-1], "retreat")
        return [Move([q_over], tcp=(over, rot), label="over place"), lower, Grip(False, "release"),
                *([retreat] if retreat is not None else [])]


def _seen(f: ObjectFeatures | None) -> bool:
    return f is not None and f.visible and f.centroid is not None


def _line(start: tuple[np.ndarray, np.ndarray], goal: tuple[np.ndarray, np.ndarray]):  # noqa: ANN202
    """A straight line between two tool poses: (p0, p1, r1, turn angle, distance, waypoint count, orientation slerp)."""
    (p0, r0), (p1, r1) = start, goal
    angle = Rotation.from_matrix(r0.T @ r1).magnitude()
    dist = float(np.linalg.norm(p1 - p0))
    n = max(1, math.ceil(dist / LINEAR_STEP_M), math.ceil(angle / LINEAR_STEP_RAD))
    return p0, p1, r1, angle, dist, n, Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([r0, r1])))
