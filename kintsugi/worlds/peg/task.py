"""The peg-insertion task: a trial's soft-wrist world, robot, context and scorer as an `Episode`."""

from __future__ import annotations

from typing import Any

from kintsugi.core.record import ReasonerSettings, TaskFigures
from kintsugi.core.registry import TASKS
from kintsugi.core.task import Episode, Task
from kintsugi.core.video import VideoRecorder
from kintsugi.worlds.peg.conditions import sample_params
from kintsugi.worlds.peg.config import CONDITIONS, PegTaskConfig
from kintsugi.worlds.peg.context import PegContext
from kintsugi.worlds.peg.robot import PegRobot
from kintsugi.worlds.peg.shapes import SHAPES_HELP, peg_shape
from kintsugi.worlds.peg.suites import SUITES
from kintsugi.worlds.peg.world import PegWorld

RECOVERY_SKILLS = ("fit", "align", "insert")


class PegEpisode(Episode):
    def __init__(self, cfg: PegTaskConfig, shape: str, condition: str, seed: int, video: bool) -> None:
        self.cfg, self.shape = cfg, shape
        self._params = sample_params(cfg, shape, condition, seed)
        self.video = VideoRecorder() if video else None
        self.world = PegWorld(cfg, self._params)
        self.robot = PegRobot(self.world, shape, on_tick=self.video.on_tick if self.video else None)
        self._truth = None

    def context(self, tags: frozenset[str], reasoner: ReasonerSettings, seed: int) -> PegContext:
        return PegContext(cfg=self.cfg, shape=self.shape, reasoner=reasoner)  # no seed: it would re-draw the truth

    def score(self) -> tuple[bool, TaskFigures | None]:
        self._truth = self.world.ground_truth()
        return self._truth.success, None

    @property
    def params(self) -> dict[str, Any]:
        truth = self._truth or self.world.ground_truth()
        return self._params.model_dump() | {"tip_depth_mm": round(truth.tip_depth_mm, 3),
                                            "tip_offset_mm": round(truth.tip_offset_mm, 3),
                                            "tip_offset_x_mm": round(truth.tip_offset_x_mm, 3),
                                            "tilt_deg": round(truth.tilt_deg, 3)}

    def outcome_text(self, success: bool, verdict: bool) -> str:
        return (f"outcome: ground truth G {'SUCCESS' if success else 'FAILURE'}, "
                f"framework F {'success' if verdict else 'failure'}")


class PegInsertionTask(Task):
    name = "peg-insertion"
    description = "soft-wrist peg-in-hole with contact-formation skills and recovery (system A)"
    config_type = PegTaskConfig
    system = "peg"
    variants_help = SHAPES_HELP
    default_variants = ("round", "square", "rectangle")
    conditions = CONDITIONS
    default_conditions = tuple(CONDITIONS)
    method_tag = "peg-insertion"
    reference_method = "baseline"
    default_method = "recovery"
    suites = SUITES
    """Named campaigns, `kintsugi bench peg-insertion --suite stretch`."""

    def check_variant(self, name: str, config: PegTaskConfig | None = None) -> None:
        """Raise ConfigError for an unknown peg shape (campaign validation, before any trial)."""
        peg_shape(name, config or PegTaskConfig())

    def episode(self, cfg: PegTaskConfig, variant: str, condition: str, seed: int, video: bool = False) -> PegEpisode:
        return PegEpisode(cfg, variant, condition, seed, video)


TASKS.register(PegInsertionTask.name, PegInsertionTask.description, tags=("system-a",))(PegInsertionTask)
