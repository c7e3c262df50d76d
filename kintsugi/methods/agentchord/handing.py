"""A handover counts when it is seen: both hands holding the object at once, each with both finger pads on it.

`handed_over(obj, giver, taker)` is a fact of the trial's history, with no constraint the goal check could read
at the end. So the conductor reads the hands just before a hand opens on an object the other hand holds too:
both pads of each hand on it, each hand held open by it. A hold by one pad (an object taken off its centre
keeps the closed hand open against one finger) passes the robot's hold sense, but it is no moment at which
both hands held it, which is what a handover is judged by. A handover the goal asks for that was never seen
fails the goal check (the re-plan hands the object over again), so it is never reported as done.
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.agentchord.observe import ARMS

HOLD_OPENING_M = 0.01
"""A hand holds with both pads only while the object keeps it this far open (fingers shut on each other can
press both pads on an object's top)."""


class Handing:
    """The conductor's handover witness (a mixin of `Conductor`: it reads through its robot and logs)."""

    robot: Any
    log: Any

    handover_goals: frozenset[str] = frozenset()
    """Objects the goal hands over (`handed_over(obj, ...)`), set by the method."""

    def witness_release(self, call: dict) -> None:
        """Before a hand opens: each object both hands hold is a handover, seen or not (kept in `handed`)."""
        arm = call.get("arm")
        if call.get("action") != "open_gripper" or arm not in ARMS:
            return
        states = {a: self.robot.arm_state(a) for a in ARMS}
        other = next(a for a in ARMS if a != arm)
        handed = self.__dict__.setdefault("handed", {})
        for obj in sorted(states[arm].held & states[other].held):
            seen = all(s.touching.get(obj) == 2 and s.gripper_opening_m >= HOLD_OPENING_M for s in states.values())
            handed[obj] = handed.get(obj, False) or seen
            if not seen:
                self.log.event(self.robot.sim_time, "handover not seen", f"the {arm} hand opens on {obj} while "
                               f"both hands hold it, but not both with both pads: no handover is counted")

    def seen_handovers(self) -> set[str]:
        """The objects seen handed over so far."""
        return {o for o, seen in self.__dict__.get("handed", {}).items() if seen}

    def handovers_done(self) -> bool:
        """Every handover the goal asks for was seen."""
        missing = sorted(self.handover_goals - self.seen_handovers())
        if missing:
            self.log.event(self.robot.sim_time, "goal check", f"handover not seen: {', '.join(missing)}")
        return not missing
