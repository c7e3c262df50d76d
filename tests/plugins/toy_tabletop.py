"""A toy tabletop task in one file: the left arm picks the block up and holds it clear of the table.

Built only from the tabletop world's declarations (a `TaskSpec`: objects, instruction, goal, script,
scorer) and registered in one line. Run it with
`kintsugi run toy-lift-block --plugin tests.plugins.toy_tabletop --method scripted`.
"""

from __future__ import annotations

from typing import Any

from kintsugi.core.record import TaskFigures
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.spec import TaskSpec
from kintsugi.worlds.tabletop.task import register
from kintsugi.worlds.tabletop.world import TabletopWorld

LIFT_M = 0.12
"""How far the script raises the block after grasping it."""
LIFTED_M = 0.06
"""Success: at the end the block's centre is this far above its resting height, in the left gripper."""


def script(obs: Any) -> list[dict[str, Any]]:
    return [
        {"action": "grasp", "arm": "left", "obj": "block", "pre_grasp_offset": 0.06},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, LIFT_M)},
    ]


class LiftFigures(TaskFigures):
    rise_m: float
    """How far the block's centre is above its resting height at the end."""
    max_rise_m: float
    held_left: bool
    """Both left finger pads touch the block at the end."""
    drops: int
    """Times the block came back down to the table after being raised `LIFTED_M`."""


class LiftScorer:
    """At the end the block is `LIFTED_M` up and in the left gripper; the ticks count falls on the way."""

    def __init__(self, cfg: TabletopConfig) -> None:
        self.rest_h = shape_of("block", cfg.objects).rest_height
        self.max_rise = 0.0
        self.drops = 0
        self._up = False

    def watch(self, world: TabletopWorld) -> None:
        rise = float(world.data.xpos[world.bodies["block"]][2]) - self.rest_h
        self.max_rise = max(self.max_rise, rise)
        if self._up and rise < 0.005:
            self.drops += 1
        self._up = rise >= LIFTED_M or (self._up and rise >= 0.005)

    def finish(self, world: TabletopWorld) -> tuple[bool, LiftFigures]:
        truth = world.ground_truth()
        rise = truth.objects["block"].pos[2] - self.rest_h
        f = LiftFigures(rise_m=round(rise, 4), max_rise_m=round(self.max_rise, 4),
                        held_left="block" in truth.held.get("left", []), drops=self.drops)
        return rise >= LIFTED_M and f.held_left, f


SPEC = TaskSpec(
    name="toy-lift-block",
    description="toy plugin: the left arm picks the block up and holds it clear of the table (system B)",
    objects=("block",),
    instruction="Pick up the block with the left arm and hold it up.",
    goal=("held_up(block)",),
    script=script,
    scorer=LiftScorer,
)

register(SPEC)
