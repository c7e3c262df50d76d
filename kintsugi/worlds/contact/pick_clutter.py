"""T3 pick-clutter: pick the green box out from among distractor cubes and place it on the goal disc.

Success (ground truth, at the end): the box rests on the table (lowest corner below 5 mm,
no finger pad touching it) with its centre within `clutter.goal_tol_m` of the goal, and no
distractor was shoved more than `scoring.max_disturb_m` from where it started.
"""

from __future__ import annotations

import math

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import PickClutterConfig
from kintsugi.worlds.contact.objects import Marker, Physics, Placement, box
from kintsugi.worlds.contact.pick_box import draw_box
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup, lowest_z, nominal
from kintsugi.worlds.contact.world import EvaluationWorld, Scene

DISTRACTOR_RGBA = (0.75, 0.75, 0.2, 1.0)
SPREAD_DEG = (-25.0, 25.0)
"""Each distractor sits at its evenly spaced angle round the box plus a draw from this range."""


class ClutterDetails(StrictModel):
    goal_distance_m: float
    lowest_z_m: float
    held: bool
    max_disturb_m: float
    """Largest displacement of a distractor from its start."""


class PlaceScorer:
    def __init__(self, cfg: PickClutterConfig, setup: TrialSetup) -> None:
        self.cfg = cfg
        self.goal = np.array(cfg.clutter.goal_m)
        self.starts = {k: np.array([p.x, p.y]) for k, p in setup.scene.start.items() if k != "box"}

    def reset(self) -> None:
        pass

    def watch(self, world: EvaluationWorld) -> None:
        pass

    def finish(self, world: EvaluationWorld) -> tuple[bool, ClutterDetails]:
        pos, _ = world.object_pose("box")
        dist = float(np.linalg.norm(pos[:2] - self.goal))
        z = lowest_z(world, "box")
        held = world.touching_pads("box")
        disturb = max((float(np.linalg.norm(world.object_pose(k)[0][:2] - s)) for k, s in self.starts.items()),
                      default=0.0)
        ok = dist <= self.cfg.clutter.goal_tol_m and z < 0.005 and not held and disturb <= self.cfg.scoring.max_disturb_m
        return ok, ClutterDetails(goal_distance_m=round(dist, 5), lowest_z_m=round(z, 5), held=held,
                                  max_disturb_m=round(disturb, 5))


def build(cfg: PickClutterConfig, d: Drawer) -> TrialSetup:
    geo, truth, place, nom = draw_box(d, "box", cfg.box)
    c = cfg.clutter
    geometry, start, truths, noms = {"box": geo}, {"box": place}, {"box": truth}, {"box": nom}
    for i in range(c.distractors):
        key = f"clutter_{i}"
        edge = d.physics(f"{key}.size_m", c.size_m)
        mass = d.physics(f"{key}.mass_kg", c.mass_kg)
        ring = d.pose(f"{key}.ring_m", c.ring_m)
        angle = math.radians(360.0 * i / c.distractors + 90.0 + d.pose(f"{key}.angle_deg", SPREAD_DEG))
        yaw = d.pose(f"{key}.yaw_deg", (-45.0, 45.0))
        geometry[key] = box((edge, edge, edge), DISTRACTOR_RGBA)
        start[key] = Placement(x=place.x + ring * math.cos(angle), y=place.y + ring * math.sin(angle), yaw_deg=yaw)
        truths[key] = Physics(mass_kg=mass, friction=truth.friction)
        noms[key] = nominal(c.mass_kg, cfg.box.friction)
    markers = {"goal": Marker(x=c.goal_m[0], y=c.goal_m[1], radius=c.goal_tol_m)}
    return TrialSetup(scene=Scene(geometry=geometry, start=start, markers=markers), truth=truths, nominal=noms,
                      params=dict(d.drawn))


TASK = ContactTaskDef(
    name="pick-clutter", description="T3: pick a box out of clutter and place it on the goal disc (system C)",
    instruction="Pick up the green box from among the yellow cubes and put it down on the green disc.",
    config_type=PickClutterConfig, build=build, scorer=PlaceScorer, target="box",
    reference_method="expert-fsm",
)
