"""A toy tabletop task in one file: the left arm lifts the block and sets it back down where it was.

Built only from the tabletop world's declarations (a `TaskSpec`: objects, instruction, goal, script,
scorer) and registered in one line. Run it with
`kintsugi run toy-lift-block --plugin tests.plugins.toy_tabletop --method scripted`.
"""

from __future__ import annotations

from typing import Any

from kintsugi.core.record import TaskFigures
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.spec import TaskSpec, at_rest, held, on_table
from kintsugi.worlds.tabletop.task import register
from kintsugi.worlds.tabletop.world import TabletopWorld

LIFT_M = 0.12
"""How far the script raises the block after grasping it."""
LIFTED_M = 0.08
"""Success needs the block's centre this far above its resting height at some instant."""


def script(obs: Any) -> list[dict[str, Any]]:
    x, y, _ = obs.objects["block"].centroid
    return [
        {"action": "grasp", "arm": "left", "obj": "block", "pre_grasp_offset": 0.06},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, LIFT_M)},
        {"action": "place", "arm": "left", "x": x, "y": y},
        {"action": "back", "arm": "left"},
    ]


class LiftFigures(TaskFigures):
    max_rise_m: float
    """Highest the block's centre rose above its resting height."""
    lifted: bool
    on_table: bool
    at_rest: bool
    released: bool


class LiftScorer:
    """Lifted at least `LIFTED_M` at some tick; at the end resting on the table, still, and let go."""

    def __init__(self, cfg: TabletopConfig) -> None:
        self.cfg = cfg
        self.rest_h = shape_of("block", cfg.objects).rest_height
        self.max_rise = 0.0

    def watch(self, world: TabletopWorld) -> None:
        self.max_rise = max(self.max_rise, float(world.data.xpos[world.bodies["block"]][2]) - self.rest_h)

    def finish(self, world: TabletopWorld) -> tuple[bool, LiftFigures]:
        truth = world.ground_truth()
        f = LiftFigures(max_rise_m=round(self.max_rise, 4), lifted=self.max_rise >= LIFTED_M,
                        on_table=on_table(truth, "block", self.rest_h),
                        at_rest=at_rest(truth, "block", self.cfg.scoring.rest_speed_m_s),
                        released=not held(truth, "block"))
        return f.lifted and f.on_table and f.at_rest and f.released, f


SPEC = TaskSpec(
    name="toy-lift-block",
    description="toy plugin: the left arm lifts the block and sets it back down (system B)",
    objects=("block",),
    instruction="Lift the block with the left arm and put it back down where it was.",
    goal=("lifted(block)", "on_table(block)", "released(block)"),
    script=script,
    scorer=LiftScorer,
)

register(SPEC)
