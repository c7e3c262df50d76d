"""Ground-truth judges a declared contact task composes: an object brought onto a goal disc, with how it got
there (slid, never lifted; rolled; never touching an obstacle) and how it ended (at rest, released, upright
or lying). Scorers only: they read the evaluation world, never shown to a method.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.objects import AXES
from kintsugi.worlds.contact.spec import TrialSetup, lowest_z
from kintsugi.worlds.contact.world import EvaluationWorld, rotate, tilt_deg

AT_REST_M_S = 0.01
AT_REST_RAD_S = 0.2


class GoalScoring(StrictModel):
    """How a goal-disc task is judged (the disc's own radius is the tolerance on the object's centre)."""

    max_lift_m: float = Field(0.01, gt=0)
    """The object's lowest point never rose higher than this: it was slid or rolled, not carried."""
    max_tilt_deg: float | None = Field(None, gt=0, lt=180)
    """Stays on its base: its up axis ends within this of vertical (None: not judged)."""
    lying: bool = False
    """A cylinder's axis ends horizontal (within 15 degrees): it lies on its side."""
    min_roll_deg: float | None = Field(None, gt=0)
    """It turned at least this far about its own long axis (rolled, not dragged); None: not judged."""
    avoid: tuple[str, ...] = ()
    """Fixtures or objects it must never touch."""


class GoalDetails(StrictModel):
    goal_distance_m: float
    """Distance of the object's centre from the disc's centre (xy) at the end."""
    on_goal: bool
    at_rest: bool
    released: bool
    max_lift_m: float
    tilt_deg: float
    roll_deg: float
    """Accumulated turn about its own long axis."""
    touched: list[str]
    """Which of the fixtures or objects to avoid it touched."""


class GoalScorer:
    """Success: the object's centre ends within the goal disc, at rest, released by the hand, and every
    judged condition of `GoalScoring` holds over the whole attempt."""

    def __init__(self, obj: str, marker: str, scoring: GoalScoring, setup: TrialSetup) -> None:
        self.obj, self.scoring = obj, scoring
        self.marker = setup.scene.markers[marker]
        self.part = setup.scene.geometry[obj].parts[0]
        self.reset()

    def reset(self) -> None:
        self.max_lift, self.roll, self.touched = 0.0, 0.0, set()
        self._last_t: float | None = None

    def watch(self, world: EvaluationWorld) -> None:
        t = float(world.data.time)
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        self.max_lift = max(self.max_lift, lowest_z(world, self.obj))
        _, ang = world.object_velocity(self.obj)  # a free joint's angular velocity is in the body's frame
        self.roll += abs(float(ang[AXES[self.part.axis]])) * dt
        for other in self.scoring.avoid:
            if world.in_contact(self.obj, other):
                self.touched.add(other)

    def finish(self, world: EvaluationWorld) -> tuple[bool, GoalDetails]:
        s = self.scoring
        pos, quat = world.object_pose(self.obj)
        lin, ang = world.object_velocity(self.obj)
        dist = float(math.hypot(pos[0] - self.marker.x, pos[1] - self.marker.y))
        at_rest = bool(np.linalg.norm(lin) < AT_REST_M_S and np.linalg.norm(ang) < AT_REST_RAD_S)
        released = not world.touching_pads(self.obj) and not bool(np.linalg.norm(world.pusher_force(self.obj)) > 0.05)
        tilt = float(tilt_deg(quat))
        lift = max(self.max_lift, lowest_z(world, self.obj))
        axis = np.zeros(3)
        axis[AXES[self.part.axis]] = 1.0
        ok = dist <= self.marker.radius and at_rest and released and lift <= s.max_lift_m and not self.touched
        if s.max_tilt_deg is not None:
            ok = ok and tilt <= s.max_tilt_deg
        if s.lying:
            ok = ok and abs(float(rotate(quat, axis)[2])) < math.sin(math.radians(15))
        if s.min_roll_deg is not None:
            ok = ok and math.degrees(self.roll) >= s.min_roll_deg
        return bool(ok), GoalDetails(goal_distance_m=round(dist, 5), on_goal=dist <= self.marker.radius,
                                     at_rest=at_rest, released=released, max_lift_m=round(lift, 5),
                                     tilt_deg=round(tilt, 2), roll_deg=round(math.degrees(self.roll), 1),
                                     touched=sorted(self.touched))
