"""slide-puck: slide a wide wooden puck across the open table onto a goal disc.

The puck (a cylinder standing on its flat face) is wider than the gripper opens, so it cannot be picked;
there is no wall or fixture to push it against, so it must be pushed and stopped on the disc by the
hand alone. Success (ground truth, at the end): the puck's centre within the disc, at rest, released,
still standing on its face, and it never left the table (its lowest point never rose 1 cm).
"""

from __future__ import annotations

from kintsugi.worlds.contact.config import ContactConfig, ControlSection, MarkerSection, ObjectSection
from kintsugi.worlds.contact.declare import declared_setup
from kintsugi.worlds.contact.judge import GoalScorer, GoalScoring
from kintsugi.worlds.contact.spec import ContactTaskDef


class SlidePuckConfig(ContactConfig):
    puck: ObjectSection = ObjectSection(
        shape="cylinder", label="wooden puck", material="wood", size_m=((0.11, 0.13), (0.025, 0.03)),
        mass_kg=(0.15, 0.35), friction=(0.3, 0.5), x_m=(-0.06, 0.0), y_m=(-0.06, 0.06), colour="red")
    goal: MarkerSection = MarkerSection(x_m=(0.13, 0.19), y_m=(-0.06, 0.06), radius_m=0.03, label="green disc")
    scoring: GoalScoring = GoalScoring(max_tilt_deg=15.0)
    control: ControlSection = ControlSection(episode_s=16.0)


TASK = ContactTaskDef(
    name="slide-puck", description="slide a wide puck across the open table onto a goal disc (system C)",
    instruction="Push the wooden puck onto the green disc.",
    config_type=SlidePuckConfig, build=declared_setup, target="puck",
    scorer=lambda cfg, setup: GoalScorer("puck", "goal", cfg.scoring, setup),
)
