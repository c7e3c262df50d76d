"""push-around: push a box onto a goal disc that a fixed post stands in front of, going round the post.

The post stands between the box and the disc, so a straight push jams the box against it: the box
must be pushed sideways past the post first. Success (ground truth, at the end): the box's centre
within the disc, at rest, released, it never touched the post and never left the table (pushed, not
carried over).
"""

from __future__ import annotations

from kintsugi.worlds.contact.config import (ContactConfig, ControlSection, FixtureSection, MarkerSection,
                                            ObjectSection)
from kintsugi.worlds.contact.declare import declared_setup
from kintsugi.worlds.contact.judge import GoalScorer, GoalScoring
from kintsugi.worlds.contact.spec import ContactTaskDef


class PushAroundConfig(ContactConfig):
    box: ObjectSection = ObjectSection(
        shape="box", label="red box", material="cardboard", size_m=((0.05, 0.055), (0.05, 0.055), (0.045, 0.05)),
        mass_kg=(0.15, 0.3), friction=(0.3, 0.5), x_m=(-0.04, 0.0), y_m=(-0.02, 0.02), yaw_deg=(-10.0, 10.0),
        colour="red")
    post: FixtureSection = FixtureSection(size_m=(0.04, 0.04, 0.10), x_m=(0.09, 0.11), y_m=(-0.01, 0.01),
                                          label="grey post")
    goal: MarkerSection = MarkerSection(x_m=(0.19, 0.22), y_m=(-0.02, 0.02), radius_m=0.035, label="green disc")
    scoring: GoalScoring = GoalScoring(avoid=("post",))
    control: ControlSection = ControlSection(episode_s=22.0)


TASK = ContactTaskDef(
    name="push-around", description="push a box round a fixed post onto a goal disc (system C)",
    instruction="Push the red box onto the green disc without touching the grey post.",
    config_type=PushAroundConfig, build=declared_setup, target="box",
    scorer=lambda cfg, setup: GoalScorer("box", "goal", cfg.scoring, setup),
)
