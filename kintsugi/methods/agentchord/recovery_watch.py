"""Watching a recovery branch while it runs (no reasoning, as for the nominal edges).

A recovery can be disturbed too: at drop p = 0.10 per action, a four-action stand-up loses its object about
a third of the time. Two checks, both from the robot's own senses:
- `LossWatch`, every control step: an object the recovery means a hand to hold, which both finger pads held
  during this edge, is no longer touched while the hand is still commanded closed (a drop; an opening the edge
  commands is no failure); and after a grasp, a hand that closed on nothing;
- `unmet`, after each recovery edge: its target sub-goal's constraints, read from the features.
Either sends the conductor back to the same failure context, whose branch was planned from the same state.
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.agentchord.observe import ARMS
from kintsugi.methods.agentchord.arranger import arm_calls
from kintsugi.taskgraph.model import Edge, Node

LOSS_WINDOW = 3
"""Control steps the loss must persist (Eq. 12's W, as for the nominal drop monitors)."""


class LossWatch:
    """A per-control-step observer: True (interrupt) once a held object has been lost for LOSS_WINDOW steps."""

    def __init__(self, robot: Any, objects: set[str] | None = None) -> None:
        self.robot = robot
        self.objects = objects
        """Only these are watched (None: any object both pads hold): what the recovery means a hand to hold,
        from `held_in_failure` and `named` (not a tray wall pinched beside the capsule a hand closed on)."""
        self.held: dict[str, set[str]] = {a: set() for a in ARMS}
        self.count = 0
        self.lost: str | None = None
        self.at: int | None = None

    def __call__(self, step: Any) -> bool:
        if self.lost is not None:
            return True
        missing = []
        for arm in ARMS:
            sense = self.robot.grip_sense(arm)
            if not sense.closed:
                self.held[arm] = set()
                continue
            missing += [f"{arm} lost {o}" for o in sorted(self.held[arm] - sense.touching)]
            self.held[arm] |= sense.touching if self.objects is None else sense.touching & self.objects
        self.count = self.count + 1 if missing else 0
        if self.count >= LOSS_WINDOW:
            self.lost, self.at = ", ".join(missing), step.index
            return True
        return False


    def check_grasp(self, action: Any) -> str | None:
        """After each action: what was lost so far, or a grasp whose hand holds nothing (closed on air)."""
        if self.lost is None and action.name == "grasp" and isinstance(arm := action.args.get("arm"), str):
            if not self.robot.grip_sense(arm).touching:
                self.lost, self.at = f"{arm} grasp closed on nothing", int(getattr(self.robot, "control_steps", 0))
        return self.lost


def held_in_failure(failed: Edge) -> set[str]:
    """What the failed edge's drop checks watched in a hand."""
    return {m.check.object for m in failed.monitors if m.check.kind == "touching"}


def named(edge: Edge) -> set[str]:
    """The objects the edge's actions name (a two-arm `drive` through its per-arm calls)."""
    return {args["obj"] for _, args in arm_calls(edge) if isinstance(args.get("obj"), str)}


def watched(node: Node) -> set[str]:
    """Objects the node's constraints read."""
    return {e for c in node.constraints for e, role, _ in c.refs() if role != "arm"}


def unmet(node: Node, features: Any) -> str | None:
    """The node's violated constraints by kind (NaN, undecided, is not a violation), or None."""
    bad = [c.kind for c in node.constraints if c.evaluate(features) > 0.0]
    return ", ".join(bad) if bad else None
