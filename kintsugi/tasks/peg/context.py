"""What a peg-insertion method is given besides the robot: config, taught goals, goal images."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from kintsugi.tasks.peg.config import PegTaskConfig
from kintsugi.tasks.peg.goals import full_goals, load_goals
from kintsugi.tasks.peg.skills import SEQUENCE, execute_skill
from kintsugi.tasks.peg.world import HOME_POSE, PegWorld, TrialParams
from kintsugi.trial import ReasonerSettings

TASK_TEXT = (
    "Insert the {shape} peg held by the soft-wrist gripper into the hole in the board, "
    "at least 10 mm deep, using the contact-formation skills approach, contact, fit, align, insert."
)


@dataclass
class PegContext:
    cfg: PegTaskConfig
    shape: str
    seed: int
    reasoner: ReasonerSettings = field(default_factory=ReasonerSettings)
    goals: dict[str, dict[str, float]] = field(default_factory=load_goals)

    @property
    def task_text(self) -> str:
        return TASK_TEXT.format(shape=self.shape)

    def full_goals(self) -> dict[str, np.ndarray]:
        return full_goals(self.goals, HOME_POSE)

    def goal_images(self) -> dict[str, np.ndarray]:
        """Terminal images of each skill in the default condition (recorded like the paper's I_g)."""
        return _goal_images(self.cfg.model_dump_json(), self.shape, tuple(
            (s, tuple(sorted(v.items()))) for s, v in self.goals.items()))


@lru_cache(maxsize=16)
def _goal_images(cfg_json: str, shape: str, goals_key: tuple) -> dict[str, np.ndarray]:
    cfg = PegTaskConfig.model_validate_json(cfg_json)
    goals = {s: dict(v) for s, v in goals_key}
    world = PegWorld(cfg, TrialParams(shape=shape))
    try:
        targets = full_goals(goals, HOME_POSE)
        return {skill: execute_skill(world, skill, targets[skill]).image for skill in SEQUENCE}
    finally:
        world.close()
