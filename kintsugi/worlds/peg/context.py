"""What a peg-insertion method is given besides the robot: config, taught goals, goal images.

No trial seed and no trial parameters: the seed would let a method re-draw the
trial's truth. The goal images are recorded once per (config, shape, goals) in
the default condition, like the paper's I_g, and that recording doubles as the
calibration of the taught goals: if they no longer insert the peg there, the
images would show a failure as the goal, so this is an error telling the user
to re-teach (see `GoalImages`).
"""

from __future__ import annotations

import json
import shlex
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import DEFAULT_GOALS_FILE, full_goals, load_goals
from kintsugi.worlds.peg.robot import insert_requirements
from kintsugi.worlds.peg.skills import SEQUENCE, execute_skill
from kintsugi.worlds.peg.world import HOME_POSE, PegWorld, TrialParams
from kintsugi.core.record import ReasonerSettings

TASK_TEXT = (
    "Insert the {shape} peg held by the soft-wrist gripper into the hole in the board: its tip at least "
    "{depth:g} mm below the board top inside the opening, and its axis within {tilt:.1f} degrees of vertical. "
    "Use the contact-formation skills approach, contact, fit, align, insert."
)
"""Depth and tilt come from the config's scoring values (what ground truth G checks); never the randomization."""
TEACH_SCRIPT = "bench/teach_goals.py"


@dataclass
class PegContext:
    cfg: PegTaskConfig
    shape: str
    reasoner: ReasonerSettings = field(default_factory=ReasonerSettings)
    goals: dict[str, dict[str, float]] | None = None
    """Per-skill taught goals (mm / deg); None loads `control.goals_file` (default: the shipped file)."""

    def __post_init__(self) -> None:
        if self.goals is None:
            self.goals = load_goals(self.cfg.control.goals_file)

    @property
    def task_text(self) -> str:
        depth, tilt = insert_requirements(self.cfg)
        return TASK_TEXT.format(shape=self.shape, depth=round(depth, 1), tilt=tilt)

    def full_goals(self) -> dict[str, np.ndarray]:
        return full_goals(self.goals, HOME_POSE)

    def goal_images(self) -> dict[str, np.ndarray]:
        """Terminal images of each skill in the default condition (recorded like the paper's I_g).

        Raises ConfigError when the taught goals do not insert the peg in the default condition
        of this config: the insert goal image would then show a failed insertion.
        """
        recorded = _goal_images(self.cfg.model_dump_json(), self.shape, _goals_key(self.goals))
        if not recorded.inserted:
            raise ConfigError(_reteach_message(self.cfg, self.shape, recorded))
        return recorded.images


@dataclass(frozen=True)
class GoalImages:
    """One default-condition run of the taught goals: each skill's terminal image, and whether
    the peg ended inserted (the world's own ground truth; default condition only, never a trial's)."""

    images: dict[str, np.ndarray]
    inserted: bool
    tip_depth_mm: float


def _goals_key(goals: dict[str, dict[str, float]]) -> tuple:
    return tuple((s, tuple(sorted(v.items()))) for s, v in goals.items())


@lru_cache(maxsize=16)
def _goal_images(cfg_json: str, shape: str, goals_key: tuple) -> GoalImages:
    """Cached per process, so a campaign pays the default-condition run once per cell, not per trial."""
    cfg = PegTaskConfig.model_validate_json(cfg_json)
    goals = {s: dict(v) for s, v in goals_key}
    world = PegWorld(cfg, TrialParams(shape=shape))  # the default condition: no randomized truth
    try:
        targets = full_goals(goals, HOME_POSE)
        images = {skill: execute_skill(world, skill, targets[skill]).image for skill in SEQUENCE}
        truth = world.ground_truth()
        return GoalImages(images=images, inserted=truth.success, tip_depth_mm=round(truth.tip_depth_mm, 1))
    finally:
        world.close()


def config_changes(cfg: PegTaskConfig) -> list[str]:
    """`key=value` for every config value that differs from the default, as `--set` takes them."""
    out: list[str] = []

    def walk(now: object, default: object, path: str) -> None:
        if isinstance(now, dict) and isinstance(default, dict):
            for key in now:
                walk(now[key], default.get(key), f"{path}.{key}" if path else key)
        elif now != default:
            out.append(f"{path}={_as_override(now)}")

    walk(cfg.model_dump(mode="json"), PegTaskConfig().model_dump(mode="json"), "")
    return out


def _as_override(value: object) -> str:
    return value if isinstance(value, str) else json.dumps(value, separators=(",", ":"))


def _reteach_message(cfg: PegTaskConfig, shape: str, recorded: GoalImages) -> str:
    changes = [c for c in config_changes(cfg) if not c.startswith("control.goals_file=")]
    source = cfg.control.goals_file or str(DEFAULT_GOALS_FILE)
    where = f"with {', '.join(changes)}" if changes else "with the default config"
    sets = " ".join(f"--set {shlex.quote(c)}" for c in changes)
    return (
        f"the taught goals ({source}) do not insert the {shape} peg in the default condition {where}: "
        f"the tip ends {recorded.tip_depth_mm:.1f} mm below the board top and ground truth says not inserted, "
        f"so the insert goal image would show a failure and recovery would chase it. Re-teach the goals for this "
        f"config: .venv/bin/python {TEACH_SCRIPT} {sets + ' ' if sets else ''}--shapes {shape} --out goals.json, "
        f"then add --set control.goals_file=goals.json"
    )
