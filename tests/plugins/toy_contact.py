"""A toy contact task in one file: raise a small cube off the table, by any grasp.

Built only from the contact world's declarations (a `ContactTaskDef`: config, draws, scorer) and
registered in one line. It has no hand-written expert, so its reference method is `coral` (the
`ContactTaskDef` default), which formulates its costs from the instruction's words.
"""

from __future__ import annotations

from pydantic import Field

from kintsugi.core.record import TaskFigures
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import BoxSection, ContactConfig, ControlSection
from kintsugi.worlds.contact.pick_box import draw_box
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup, lowest_z
from kintsugi.worlds.contact.task import register
from kintsugi.worlds.contact.world import EvaluationWorld, Scene


class RaiseCubeConfig(ContactConfig):
    cube: BoxSection = BoxSection(size_m=((0.04, 0.05), (0.04, 0.05), (0.04, 0.05)), mass_kg=(0.1, 0.3),
                                  friction=(0.4, 0.7), x_m=(0.02, 0.10), y_m=(-0.06, 0.06), yaw_deg=(-20, 20),
                                  rgba=(0.9, 0.75, 0.1, 1.0))
    raise_m: float = Field(0.03, gt=0)
    """Success: the cube's lowest corner this high above the table at some instant."""
    control: ControlSection = ControlSection(episode_s=8.0)


class RaiseFigures(TaskFigures):
    max_lowest_z_m: float
    raised: bool


class RaiseScorer:
    def __init__(self, raise_m: float) -> None:
        self.raise_m = raise_m
        self.reset()

    def reset(self) -> None:
        self.max_z = 0.0

    def watch(self, world: EvaluationWorld) -> None:
        self.max_z = max(self.max_z, lowest_z(world, "cube"))

    def finish(self, world: EvaluationWorld) -> tuple[bool, RaiseFigures]:
        raised = self.max_z >= self.raise_m
        return raised, RaiseFigures(max_lowest_z_m=round(self.max_z, 5), raised=raised)


def build(cfg: RaiseCubeConfig, d: Drawer) -> TrialSetup:
    geo, truth, place, nom = draw_box(d, "cube", cfg.cube)
    return TrialSetup(scene=Scene(geometry={"cube": geo}, start={"cube": place}), truth={"cube": truth},
                      nominal={"cube": nom}, params=dict(d.drawn))


TASK = ContactTaskDef(
    name="toy-raise-cube", description="toy plugin: raise a small cube off the table (system C)",
    instruction="Lift the cube off the table.", config_type=RaiseCubeConfig, build=build,
    scorer=lambda cfg, setup: RaiseScorer(cfg.raise_m), target="cube",
)

register(TASK)
