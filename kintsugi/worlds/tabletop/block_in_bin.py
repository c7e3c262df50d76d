"""Task `block-in-bin`: put the orange block into the grey bin.

One file: the two declared objects (a block; an open box, the bin, with 6 mm walls), the instruction and
goal, the ground-truth scorer (the block's centre over the bin's floor, its bottom below the rim, lying flat;
the bin flat on the table; both released and at rest) and the scripted reference sequence.
"""

from __future__ import annotations

from typing import Any

from kintsugi.worlds.tabletop.config import ObjectSection
from kintsugi.worlds.tabletop.judge import goal_scorer
from kintsugi.worlds.tabletop.spec import TaskSpec

LIFT_M = 0.12
WALL_M = 0.006
FLOOR_CLEAR_M = 0.008

OBJECTS = {
    "orange_block": ObjectSection(shape="box", kind="block", colour="orange", size_m=(0.02, 0.02, 0.02), mass_kg=0.08,
                           x_m=(0.34, 0.42), y_m=(0.16, 0.26), yaw_deg=(-25.0, 25.0)),
    "bin": ObjectSection(shape="box", kind="bin", colour="grey", size_m=(0.10, 0.10, 0.03), wall_m=WALL_M,
                         mass_kg=0.4, x_m=(0.44, 0.50), y_m=(-0.14, -0.06)),
}


def script(obs: Any) -> list[dict[str, Any]]:
    c = obs.objects["bin"].centroid
    return [
        {"action": "grasp", "arm": "left", "obj": "orange_block", "pre_grasp_offset": 0.06},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, LIFT_M)},
        {"action": "place", "arm": "left", "x": c[0], "y": c[1], "z_offset": WALL_M + FLOOR_CLEAR_M},
        {"action": "back", "arm": "left"},
    ]


SPEC = TaskSpec(
    name="block-in-bin",
    description="block in bin: put the block into the open bin (system B, a task of its own)",
    objects=tuple(OBJECTS),
    declared=OBJECTS,
    instruction="Put the orange block into the grey bin.",
    goal=("inside(orange_block, bin)", "released(orange_block)", "flat(bin)"),
    script=script,
    scorer=goal_scorer(("inside", "orange_block", "bin"), ("flat", "orange_block"), ("flat", "bin"), ("on_table", "bin"),
                       ("released", "orange_block"), ("released", "bin"), ("at_rest", "orange_block"), ("at_rest", "bin")),
    shift=("bin", (0, 1)),
)
