"""Task `flank-box`: put the green can to the left of the brown box and the yellow can to the right of it.

One file: the three declared objects (two cans, upright cylinders taken side-on; a box that stays where it
is), the instruction and goal, the ground-truth scorer (each can 6-28 cm to its side of the box's centre,
within 8 cm of it front to back, standing on the table, released, at rest: what the instruction asks, and
nothing about the box's own pose, which it does not mention) and the scripted reference sequence (each arm
places the can on its own side).
"""

from __future__ import annotations

from typing import Any

from kintsugi.worlds.tabletop.config import ObjectSection
from kintsugi.worlds.tabletop.judge import goal_scorer
from kintsugi.worlds.tabletop.spec import TaskSpec

LIFT_M = 0.10
SIDE_M = 0.15

OBJECTS = {
    "box": ObjectSection(shape="box", kind="box", colour="brown", size_m=(0.04, 0.05, 0.04), mass_kg=0.5,
                         x_m=(0.44, 0.50), y_m=(-0.04, 0.04), yaw_deg=(-15.0, 15.0)),
    "green_can": ObjectSection(shape="cylinder", kind="can", colour="green", size_m=(0.028, 0.055, 0.0),
                               mass_kg=0.15, x_m=(0.32, 0.38), y_m=(0.18, 0.26)),
    "yellow_can": ObjectSection(shape="cylinder", kind="can", colour="yellow", size_m=(0.028, 0.055, 0.0),
                                mass_kg=0.15, x_m=(0.32, 0.38), y_m=(-0.26, -0.18)),
}


def script(obs: Any) -> list[dict[str, Any]]:
    box = obs.objects["box"].centroid
    plan = {}
    for arm, can, side in (("left", "green_can", 1.0), ("right", "yellow_can", -1.0)):
        plan[arm] = [
            {"action": "grasp", "arm": arm, "obj": can, "pre_grasp_offset": 0.08},
            {"action": "move_by_offset", "arm": arm, "dxyz": (0.0, 0.0, LIFT_M)},
            {"action": "place", "arm": arm, "x": box[0], "y": box[1] + side * SIDE_M},
            {"action": "back", "arm": arm},
        ]
    return [{"action": "drive", "left": a, "right": b} for a, b in zip(plan["left"], plan["right"])]


SPEC = TaskSpec(
    name="flank-box",
    description="flank box: a can to the left of the box and one to its right (system B, a task of its own)",
    objects=tuple(OBJECTS),
    declared=OBJECTS,
    instruction="Put the green can to the left of the brown box and the yellow can to the right of it.",
    goal=("left_of(green_can, box)", "right_of(yellow_can, box)", "upright(green_can)", "upright(yellow_can)",
          "released(green_can)", "released(yellow_can)"),
    script=script,
    scorer=goal_scorer(("left_of", "green_can", "box"), ("right_of", "yellow_can", "box"),
                       ("upright", "green_can"), ("upright", "yellow_can"), ("on_table", "green_can"),
                       ("on_table", "yellow_can"), ("released", "green_can"), ("released", "yellow_can"),
                       ("at_rest", "green_can"), ("at_rest", "yellow_can")),
    shift=("box", (0, 1)),
    knock=("green_can", (0, 0)),
)
