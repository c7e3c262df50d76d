"""The `push` action's motion program: the closed hand comes down behind the object and moves it along.

Where the pads meet the object comes from perception only: its perceived centre, the capsule over its axis
ends that `clearance` takes it for, and its perceived top. Every pose is solved before anything moves, as for
the other actions, so a push the arm cannot make refuses (ik_failed, or clipped to the workspace) with nothing
moved. The object moves by contact alone: the hand's path is planned, the object's is not.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from kintsugi.worlds.tabletop import actions as A
from kintsugi.worlds.tabletop.arm_model import PAD_HALF
from kintsugi.worlds.tabletop.clearance import across, top_z
from kintsugi.worlds.tabletop.motion import Grip, Move, Step

START_CLEAR_M = 0.012
"""A push from beside the object starts this far behind it (its perceived width errs by millimetres)."""
PRESS_M = 0.008
"""A push from above starts this far into the object's perceived surface: the pads press on it, and friction
draws it along."""
LOW_M = 0.006
"""The pads' lowest point stays this far above the table."""
HOVER_M = 0.04
"""The hand comes down from this far above the object's top..."""
LOW_HOVER_M = 0.02
"""...or, where the arm does not reach that high so far out, from this far above the push's start."""


def reach_along(f: Any, u: np.ndarray) -> float:
    """How far the perceived object extends from its centre in horizontal direction `u`: its axis ends' reach
    that way, and across the axis half its perceived width (a lying cylinder's support)."""
    c = np.asarray(f.centroid, float)[:2]
    ends = [f.extremes.get(k) for k in ("axis_pos", "axis_neg")] if f.extremes else []
    arms = [np.asarray(e, float)[:2] - c for e in ends if e is not None]
    along = max([0.0, *(abs(float(v @ u)) for v in arms)])
    length = max([0.0, *(float(np.linalg.norm(v)) for v in arms)])
    cos = along / length if length > 1e-3 else 0.0
    return along + across(f) * math.sqrt(max(0.0, 1.0 - cos * cos))


def push_rotation(u: np.ndarray, pitch_deg: float, turn_deg: float = 0.0) -> np.ndarray:
    """The hand pointing down, its x axis along the push (turned by `turn_deg` about the vertical), tilted by
    `pitch_deg` about its closing axis."""
    down = Rotation.from_euler("ZY", [math.atan2(u[1], u[0]) + math.radians(turn_deg), math.pi])
    return (down * Rotation.from_euler("y", pitch_deg, degrees=True)).as_matrix()


def contact_tip(f: Any, u: np.ndarray, contact_deg: float) -> np.ndarray:
    """Where the pads' tip starts: behind the object (against `u`) at `contact_deg` from its top (90: beside it,
    low; 0: on its top, pressed in by PRESS_M)."""
    c = np.asarray(f.centroid, float)
    half_h = max(top_z(f) - c[2], 0.0)
    r = PAD_HALF[1]
    t = math.radians(contact_deg)
    if contact_deg >= 90.0 - 1e-9:
        xy = c[:2] - u * (reach_along(f, u) + r + START_CLEAR_M)
        return np.array([*xy, max(r + LOW_M, c[2] - 0.5 * half_h)])
    xy = c[:2] - u * (reach_along(f, u) + r - PRESS_M) * math.sin(t)
    return np.array([*xy, max(r + LOW_M, c[2] + (half_h + r - PRESS_M) * math.cos(t))])


def push_program(planner: Any, a: A.Push, arm: Any, feats: dict) -> list[Step]:
    """Close the hand, come down behind the object (from above it, clear of the rest), move along `dxy` (and
    the starting clearance), rise. Raises the planner's PlanError when a pose is out of reach or the hand
    holds something (it cannot push with an object in it)."""
    held = [k for k, n in arm.touching.items() if n == 2]
    if held:
        raise A.PlanError(f"the {a.arm} hand holds {held[0]}: it cannot push", ik_failed=False)
    f = planner._visible(a.obj, feats.get(a.obj))
    d = np.asarray(a.dxy, float)
    dist = float(np.linalg.norm(d))
    if dist < 1e-4:
        raise A.PlanError("a push needs a direction (dxy is zero)")
    u = d / dist
    travel = dist + (START_CLEAR_M if a.contact_deg >= 90.0 - 1e-9 else 0.0)
    what = f"{a.obj} from behind"
    tried: A.PlanError | None = None
    for flip in (0.0, 180.0):  # the closed hand is the same either way round; the wrist's limits are not
        rot = push_rotation(u, a.pitch_deg, flip)
        start = contact_tip(f, u, a.contact_deg) - PAD_HALF[2] * rot[:, 2]  # the tool centre: half a pad up
        end = start + np.array([*(u * travel), 0.0])
        # From above the object, or, where the arm does not reach that high so far out, from just above the start.
        for rise in (max(0.0, top_z(f) + HOVER_M + PAD_HALF[2] - start[2]), LOW_HOVER_M):
            hover = start + np.array([0.0, 0.0, rise])
            try:
                q_hover = planner._solve(a.arm, hover, rot, arm.q, f"the pose above {what}")
                break
            except A.PlanError as exc:
                tried = exc
        else:
            continue
        break
    else:
        assert tried is not None
        raise tried
    lifted = end + np.array([0.0, 0.0, hover[2] - start[2]])
    down = planner._linear(a.arm, (hover, rot), (start, rot), q_hover, f"the push's start behind {a.obj}",
                           f"behind {a.obj}")
    along = planner._linear(a.arm, (start, rot), (end, rot), down.waypoints[-1], f"the push's end with {a.obj}",
                            f"push {a.obj}")
    up = planner._linear(a.arm, (end, rot), (lifted, rot), along.waypoints[-1], "the pose above the push's end",
                         "rise")
    return [Grip(True, "close"), *planner._way_clear(a.arm, arm, q_hover, feats),
            Move([q_hover], tcp=(hover, rot), label=f"above {what}"), down, along, up]
