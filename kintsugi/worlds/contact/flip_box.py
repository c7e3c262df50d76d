"""T5 flip-box: tip a tall box standing on its small face over onto its side.

Success (ground truth, at the end): the box's up axis has turned at least `scoring.flip_deg`
from vertical, the box is at rest (speed below 1 cm/s and 0.2 rad/s) lying on the table
(lowest corner below 5 mm), and the hand no longer touches it.
"""

from __future__ import annotations

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import FlipBoxConfig
from kintsugi.worlds.contact.pick_box import draw_box
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup, lowest_z
from kintsugi.worlds.contact.world import EvaluationWorld, Scene, tilt_deg


class FlipDetails(StrictModel):
    tilt_deg: float
    max_tilt_deg: float
    speed_m_s: float
    lowest_z_m: float
    touched: bool


class FlipScorer:
    def __init__(self, cfg: FlipBoxConfig, setup: TrialSetup) -> None:
        self.cfg = cfg
        self.reset()

    def reset(self) -> None:
        self.max_tilt = 0.0

    def watch(self, world: EvaluationWorld) -> None:
        self.max_tilt = max(self.max_tilt, float(tilt_deg(world.object_pose("box")[1])))

    def finish(self, world: EvaluationWorld) -> tuple[bool, FlipDetails]:
        tilt = float(tilt_deg(world.object_pose("box")[1]))
        lin, ang = world.object_velocity("box")
        z = lowest_z(world, "box")
        touched = world.touching_pads("box") or bool(np.linalg.norm(world.pusher_force("box")) > 0.05)
        ok = (tilt >= self.cfg.scoring.flip_deg and np.linalg.norm(lin) < 0.01 and np.linalg.norm(ang) < 0.2
              and z < 0.005 and not touched)
        return bool(ok), FlipDetails(tilt_deg=round(tilt, 2), max_tilt_deg=round(max(self.max_tilt, tilt), 2),
                                     speed_m_s=round(float(np.linalg.norm(lin)), 4), lowest_z_m=round(z, 5),
                                     touched=touched)


def build(cfg: FlipBoxConfig, d: Drawer) -> TrialSetup:
    geo, truth, place, nom = draw_box(d, "box", cfg.box)
    return TrialSetup(scene=Scene(geometry={"box": geo}, start={"box": place}), truth={"box": truth},
                      nominal={"box": nom}, params=dict(d.drawn))


TASK = ContactTaskDef(
    name="flip-box", description="T5: tip a tall box over onto its side (system C)",
    instruction="Flip the standing box over so that it lies on its side.", config_type=FlipBoxConfig, build=build,
    scorer=FlipScorer, target="box",
    reference_method="expert-fsm",
)
