"""Task `stack-blocks`: put the red block on top of the blue block.

Everything the task needs is in this file: its two objects (declared boxes), its instruction and goal, its
scorer (ground truth: the red block's centre over the blue block's top face, its bottom on that face, both
lying flat, at rest, released) and the scripted reference sequence.
"""

from __future__ import annotations

from typing import Any

from kintsugi.worlds.tabletop.config import ObjectSection
from kintsugi.worlds.tabletop.judge import goal_scorer
from kintsugi.worlds.tabletop.spec import TaskSpec

LIFT_M = 0.10

OBJECTS = {
    "red_block": ObjectSection(shape="box", kind="block", colour="red", size_m=(0.022, 0.022, 0.022), mass_kg=0.08,
                               x_m=(0.36, 0.44), y_m=(0.14, 0.24), yaw_deg=(-20.0, 20.0)),
    "blue_block": ObjectSection(shape="box", kind="block", colour="blue", size_m=(0.03, 0.03, 0.025), mass_kg=0.2,
                                x_m=(0.40, 0.48), y_m=(-0.06, 0.04), yaw_deg=(-20.0, 20.0)),
}


def script(obs: Any) -> list[dict[str, Any]]:
    base = obs.objects["blue_block"]
    return [
        {"action": "grasp", "arm": "left", "obj": "red_block", "pre_grasp_offset": 0.06},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, LIFT_M)},
        {"action": "place", "arm": "left", "x": base.centroid[0], "y": base.centroid[1],
         "z_offset": base.extremes["top"][2]},
        {"action": "back", "arm": "left", "rise_m": 0.05},
    ]


SPEC = TaskSpec(
    name="stack-blocks",
    description="stack blocks: the red block on top of the blue one (system B, a task of its own)",
    objects=tuple(OBJECTS),
    declared=OBJECTS,
    instruction="Stack the red block on the blue block.",
    goal=("on(red_block, blue_block)", "released(red_block)", "flat(blue_block)"),
    script=script,
    scorer=goal_scorer(("on", "red_block", "blue_block"), ("flat", "red_block"), ("flat", "blue_block"),
                       ("on_table", "blue_block"), ("released", "red_block"), ("released", "blue_block"),
                       ("at_rest", "red_block"), ("at_rest", "blue_block")),
    shift=("blue_block", (0, 1)),
)
