"""roll-cylinder: roll a wooden cylinder lying on its side along the table onto a goal disc.

The cylinder lies with its axis across the table (y). Pushed at or below its axis the finger pads' grip
holds its back from turning and it mostly slides (a scripted push through the axis turns it 60-110
degrees over 20 cm); pushed above its axis it rolls (about 400 degrees over the same way), and it rolls
on after the hand stops, so the push must end short of the disc. Success (ground truth, at the end): its
centre within the disc, at rest, released, still lying on its side, it turned at least
`scoring.min_roll_deg` about its own axis (rolled, not dragged), and it never left the table.
"""

from __future__ import annotations

from kintsugi.worlds.contact.config import ContactConfig, ControlSection, MarkerSection, ObjectSection
from kintsugi.worlds.contact.declare import declared_setup
from kintsugi.worlds.contact.judge import GoalScorer, GoalScoring
from kintsugi.worlds.contact.spec import ContactTaskDef


class RollCylinderConfig(ContactConfig):
    cylinder: ObjectSection = ObjectSection(
        shape="cylinder", axis="y", label="wooden cylinder", material="wood", size_m=((0.05, 0.06), (0.10, 0.12)),
        mass_kg=(0.12, 0.25), friction=(0.4, 0.6), x_m=(-0.06, 0.0), y_m=(-0.02, 0.02), yaw_deg=(-5.0, 5.0),
        colour="brown")
    goal: MarkerSection = MarkerSection(x_m=(0.14, 0.20), y_m=(-0.02, 0.02), radius_m=0.04, label="blue disc",
                                        rgba=(0.15, 0.35, 0.9, 0.45))
    scoring: GoalScoring = GoalScoring(lying=True, min_roll_deg=180.0)
    control: ControlSection = ControlSection(episode_s=16.0)


TASK = ContactTaskDef(
    name="roll-cylinder", description="roll a lying cylinder along the table onto a goal disc (system C)",
    instruction="Roll the wooden cylinder onto the blue disc.",
    config_type=RollCylinderConfig, build=declared_setup, target="cylinder",
    scorer=lambda cfg, setup: GoalScorer("cylinder", "goal", cfg.scoring, setup),
)
