"""An object no arm can grasp where it lies is pushed back into reach, then grasped.

A knocked bottle or cup can roll to where no way of grasping it is within either arm's reach (the table's far
edge, beside the robot's body). When the grasp's own alternatives and the drag (`Reaching`) fail, the conductor
pushes the object with a closed hand towards the middle of an arm's reach (`pull_vector`), along the line from
that arm's base: from beside the object's far side where the arm reaches it, else from higher up its far side,
else pressing on its top and drawing it along. Every way is planned before anything moves, from perceived
features only. After each push the object is let come to rest and read again; once a grasp of it by an arm is
within reach the push is done (the call's own arm takes it, or a re-plan gives it to the arm that reaches it).
After MAX_PUSHES pushes that did not bring it into reach, or when no push is within reach either, the push
ends with a recorded event saying why, and the action fails as before (a recorded failure, never an error).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.methods.agentchord.reaching import grasp_alternatives, pull_vector

MAX_PUSHES = 3
CONTACTS_DEG = (90.0, 45.0, 0.0)
"""Where the pads meet the object's far side, tried in turn: beside it, halfway up, on its top."""
PITCHES_DEG = (0.0, -30.0, 30.0, -50.0, 50.0)
"""Hand tilts tried for each contact (a hand leaning in reaches farther out)."""
LEAST_PUSH_M = 0.02
FARTHEST_M = 0.9
"""No pose of an arm's hand at the table is this far from its base (horizontally): nothing is planned there."""


class Pushing:
    """The conductor's push back into reach (a mixin of `Conductor`: it acts through `_execute`, reads through
    its robot and waits with `Settling.wait_still`)."""

    robot: Any
    log: Any
    arms: set

    def grasp_reachable(self, call: dict, arm: str) -> dict | None:
        """A grasp of the call's object by `arm` (the call itself, else one of its alternatives) that the arm
        can carry out from here, or None (planned only, nothing moves)."""
        base = {k: v for k, v in call.items() if k != "grasp_offset"} | {"arm": arm}
        f = self.robot.features({call["obj"]}).get(call["obj"])
        if f is None or f.centroid is None or self.far(arm, f.centroid):
            return None
        for alt in [base, *grasp_alternatives(base, f, np.asarray(self.robot.bases[arm], float))]:
            if self.feasible(alt):
                return alt
        return None

    def far(self, arm: str, centre: Any) -> bool:
        return float(np.linalg.norm(np.asarray(centre, float)[:2] - np.asarray(self.robot.bases[arm], float)[:2])) \
            > FARTHEST_M

    def pushers(self, obj: str, centre: np.ndarray) -> list[str]:
        """The plan's arms with an empty hand within FARTHEST_M of the object, nearest first."""
        arms = [a for a in sorted(self.arms) if a in ("left", "right") and not self.far(a, centre)
                and not self.robot.arm_state(a).held]
        return sorted(arms, key=lambda a: float(np.linalg.norm(centre[:2] - np.asarray(self.robot.bases[a])[:2])))

    def push_way(self, obj: str, f: Any) -> dict | None:
        """The first push by an arm of the plan that is within its reach, or None."""
        for arm in self.pushers(obj, np.asarray(f.centroid, float)):
            move = pull_vector(f, np.asarray(self.robot.bases[arm], float))
            if float(np.linalg.norm(move)) < LEAST_PUSH_M:
                continue
            for contact in CONTACTS_DEG:
                for pitch in PITCHES_DEG:
                    push = {"action": "push", "arm": arm, "obj": obj, "dxy": [round(float(v), 4) for v in move],
                            "contact_deg": contact, "pitch_deg": pitch}
                    if self.feasible(push):
                        return push
        return None

    def push_into_reach(self, edge: Any, call: dict) -> bool:
        """Push the call's object until some arm of the plan can grasp it (at most MAX_PUSHES pushes). True
        when one can; False, with the reason recorded, when no push reaches it or the pushes did not help."""
        obj = call["obj"]
        for n in range(MAX_PUSHES):
            f = self.robot.features({obj}).get(obj)
            if f is None or f.centroid is None:
                self.log.event(self.robot.sim_time, "push into reach", f"{obj} is not seen: no push is aimed")
                return False
            push = self.push_way(obj, f)
            if push is None:
                self.log.event(self.robot.sim_time, "push into reach", f"{obj} at {np.round(f.centroid[:2], 3).tolist()}"
                               f" lies out of every arm's grasp, and no push of it is within reach either"
                               + (f" (after {n} pushes)" if n else ""))
                return False
            args = {k: v for k, v in push.items() if k != "action"}
            self.log.event(self.robot.sim_time, "push into reach", f"{obj} at {np.round(f.centroid[:2], 3).tolist()} "
                           f"lies out of every arm's grasp for {edge.id}: the {push['arm']} hand pushes it "
                           f"{push['dxy']} m (contact {push['contact_deg']:g} deg, pitch {push['pitch_deg']:g} deg)")
            self._execute(edge, "push", args, unplanned_ok=True)
            self.wait_still(push["arm"], {obj}, edge)
            reached = [a for a in sorted(self.arms) if a in ("left", "right") and self.grasp_reachable(call, a)]
            if reached:
                self.log.event(self.robot.sim_time, "push into reach", f"{obj} is within the {' and '.join(reached)}"
                               f" arm's grasp after {n + 1} push{'es' if n else ''}")
                return True
        self.log.event(self.robot.sim_time, "push into reach", f"{obj} is still out of every arm's grasp after "
                       f"{MAX_PUSHES} push{'es' if MAX_PUSHES > 1 else ''}; the action fails")
        return False
