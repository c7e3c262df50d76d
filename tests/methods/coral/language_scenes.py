"""The scenes the instruction suite (instructions.yaml) is read over: what the robot perceives, no MuJoCo."""

from __future__ import annotations

from kintsugi.methods.coral.types import FixtureView, MarkerView, ObjectState
from tests.coral_scenes import BOX, CUBES, DISC, GREEN, WALL, request

CURB = WALL.model_copy(update={"name": "curb", "label": "wooden curb", "hi_m": (0.23, 0.15, 0.02)})
BOARD = ObjectState(name="board", label="cutting board", size_m=(0.25, 0.15, 0.015), pos_m=(0.05, 0.0, 0.0075),
                    yaw_deg=2.0, upright_deg=0.0, shape="box", material="wooden")
TALL = BOX.model_copy(update={"size_m": (0.05, 0.07, 0.1), "pos_m": (0.05, 0.0, 0.05)})
PUCK = ObjectState(name="puck", label="wooden puck", size_m=(0.06, 0.06, 0.03), pos_m=(0.0, -0.05, 0.015), yaw_deg=0.0,
                   upright_deg=0.0, shape="cylinder", colour="red", material="wooden")
GOAL = MarkerView(name="goal", x_m=0.15, y_m=0.08, radius_m=0.03, label="green disc")
RED = BOX.model_copy(update={"name": "red_box", "label": "box", "colour": "red", "pos_m": (0.03, 0.08, 0.025)})
BLUE = BOX.model_copy(update={"name": "blue_box", "label": "box", "colour": "blue", "pos_m": (0.03, -0.08, 0.025)})
CYLINDER = ObjectState(name="cylinder", label="wooden cylinder", size_m=(0.05, 0.05, 0.12), pos_m=(0.05, 0.05, 0.06),
                       yaw_deg=0.0, upright_deg=0.0, shape="cylinder", material="wooden")
SPHERE = ObjectState(name="sphere", label="steel sphere", size_m=(0.05, 0.05, 0.05), pos_m=(0.0, -0.1, 0.025),
                     yaw_deg=0.0, upright_deg=0.0, shape="sphere", material="steel")

YELLOW = [c.model_copy(update={"colour": "yellow"}) for c in CUBES]
GREEN_DISC = DISC.model_copy(update={"label": "green disc"})

AROUND_BOX = BOX.model_copy(update={"label": "red box", "colour": "red", "material": "cardboard",
                                    "pos_m": (-0.02, 0.0, 0.025)})
POST = FixtureView(name="post", lo_m=(0.08, -0.02, 0.0), hi_m=(0.12, 0.02, 0.1), label="grey post")
AROUND_GOAL = MarkerView(name="goal", x_m=0.2, y_m=0.0, radius_m=0.035, label="green disc")
LYING = ObjectState(name="cylinder", label="wooden cylinder", size_m=(0.055, 0.118, 0.055), pos_m=(-0.03, 0.0, 0.0275),
                    yaw_deg=0.0, upright_deg=0.0, shape="cylinder", colour="orange", material="wood")
BLUE_DISC = MarkerView(name="goal", x_m=0.17, y_m=0.0, radius_m=0.04, label="blue disc")

SCENES = {
    "around": ([AROUND_BOX], [POST], [AROUND_GOAL]),
    "roll": ([LYING], [], [BLUE_DISC]),
    "clutter-colours": ([GREEN.model_copy(update={"colour": "green"}), *YELLOW], [], [GREEN_DISC]),
    "push": ([BOX], [WALL], []),
    "clutter": ([GREEN, *CUBES], [], [DISC]),
    "board": ([BOARD], [], []),
    "tall": ([TALL], [], []),
    "curb": ([BOX], [CURB], []),
    "puck": ([PUCK], [], [GOAL]),
    "two": ([RED, BLUE], [WALL], []),
    "cyl": ([CYLINDER, SPHERE], [WALL], []),
}


def scene_request(scene: str, text: str, contact: bool = True):  # noqa: ANN201 - a FormulationRequest
    objects, fixtures, markers = SCENES[scene]
    return request(text, objects, list(fixtures), list(markers), contact=contact)


__all__ = ["SCENES", "scene_request", "FixtureView"]
