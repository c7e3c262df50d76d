"""T2 pick-box: pick a box up off the table (lifted clear and pinched by both fingers)."""

from __future__ import annotations

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import BoxSection, PickBoxConfig
from kintsugi.worlds.contact.objects import Geometry, Physics, Placement, box
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup, lowest_z, nominal
from kintsugi.worlds.contact.world import EvaluationWorld, Scene


def draw_box(d: Drawer, key: str, s: BoxSection) -> tuple[Geometry, Physics, Placement, Physics]:
    """(geometry, true physics, start, nominal physics) of one box, drawn in a fixed order."""
    size = tuple(d.physics(f"{key}.size_{a}_m", r) for a, r in zip("xyz", s.size_m))
    phys = Physics(mass_kg=d.physics(f"{key}.mass_kg", s.mass_kg), friction=d.physics(f"{key}.friction", s.friction))
    place = Placement(x=d.pose(f"{key}.x_m", s.x_m), y=d.pose(f"{key}.y_m", s.y_m),
                      yaw_deg=d.pose(f"{key}.yaw_deg", s.yaw_deg))
    return box(size, s.rgba), phys, place, nominal(s.mass_kg, s.friction)


class PickDetails(StrictModel):
    lowest_z_m: float
    """Height of the box's lowest corner above the table at the end."""
    max_lowest_z_m: float
    pinched: bool
    """Both finger pads touch the box at the end."""


class LiftScorer:
    """Success: at the end the object's lowest point is `lift_m` above the table and both pads touch it."""

    def __init__(self, obj: str, lift_m: float) -> None:
        self.obj, self.lift_m = obj, lift_m
        self.reset()

    def reset(self) -> None:
        self.max_z = 0.0

    def watch(self, world: EvaluationWorld) -> None:
        self.max_z = max(self.max_z, lowest_z(world, self.obj))

    def finish(self, world: EvaluationWorld) -> tuple[bool, PickDetails]:
        z = lowest_z(world, self.obj)
        pinched = world.pinched(self.obj)
        return z >= self.lift_m and pinched, PickDetails(lowest_z_m=round(z, 5), max_lowest_z_m=round(self.max_z, 5),
                                                         pinched=pinched)


def build(cfg: PickBoxConfig, d: Drawer) -> TrialSetup:
    geo, truth, place, nom = draw_box(d, "box", cfg.box)
    return TrialSetup(scene=Scene(geometry={"box": geo}, start={"box": place}), truth={"box": truth},
                      nominal={"box": nom}, params=dict(d.drawn))


TASK = ContactTaskDef(
    name="pick-box", description="T2: pick a box up off the table (system C)",
    instruction="Pick up the box from the table.", config_type=PickBoxConfig, build=build,
    scorer=lambda cfg, setup: LiftScorer("box", cfg.scoring.lift_m), target="box",
    reference_method="expert-fsm",
)
