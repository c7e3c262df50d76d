"""T6 flip-wall: pivot a flat box up against a low curb (the box cannot tip on the open table: it slides).

Success (ground truth, at the end): as for flip-box (see flip_box.py): the box's up axis has
turned at least `scoring.flip_deg`, it is at rest, resting low, and the hand no longer touches it.
"""

from __future__ import annotations

from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import FlipWallConfig
from kintsugi.worlds.contact.flip_box import FlipScorer
from kintsugi.worlds.contact.pick_box import draw_box
from kintsugi.worlds.contact.push_force import wall_fixture
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup
from kintsugi.worlds.contact.world import Scene


def build(cfg: FlipWallConfig, d: Drawer) -> TrialSetup:
    geo, truth, place, nom = draw_box(d, "box", cfg.box)
    scene = Scene(geometry={"box": geo}, start={"box": place}, fixtures={"curb": wall_fixture(cfg.wall)})
    return TrialSetup(scene=scene, truth={"box": truth}, nominal={"box": nom}, params=dict(d.drawn))


TASK = ContactTaskDef(
    name="flip-wall", description="T6: flip a flat box up by pivoting it against a curb (system C)",
    instruction="Flip the flat box up onto its end, using the curb as a fixture to pivot it against.",
    config_type=FlipWallConfig, build=build, scorer=FlipScorer, target="box",
    reference_method="expert-fsm",
)
