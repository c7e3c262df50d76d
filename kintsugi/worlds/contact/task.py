"""Any contact `ContactTaskDef` as a task: a trial's evaluation world, robot, context and scorer as an `Episode`.

Methods tagged `system-c` drive it (they get a `ContactContext` and a `ContactRobot`); only
methods also tagged `oracle-physics` get the trial's true masses and frictions, its seed and the
config's ranges in their context.
The scorer watches the evaluation world at the robot's inner rate and judges the end.
"""

from __future__ import annotations

from typing import Any

from kintsugi.core.record import ReasonerSettings, TaskFigures
from kintsugi.core.registry import TASKS
from kintsugi.core.task import Episode, Task
from kintsugi.worlds.contact.conditions import CONDITIONS, Drawer
from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.worlds.contact.context import METHOD_TAG, ORACLE_TAG, ContactContext, TaskBrief, withheld
from kintsugi.worlds.contact.robot import ContactRobot
from kintsugi.worlds.contact.spec import ContactTaskDef, Scorer, TrialSetup
from kintsugi.worlds.contact.world import EvaluationWorld

VARIANTS = ("default",)


class ContactEpisode(Episode):
    def __init__(self, task: "ContactTask", cfg: ContactConfig, condition: str, seed: int, video: bool) -> None:
        self.task, self.cfg = task, cfg
        self.world, self.scorer, self.setup = task.build(cfg, condition, seed)
        self.video = None
        if video:
            from kintsugi.worlds.contact.video import ContactVideo

            self.video = ContactVideo(self.world)
        watchers = [self.scorer.watch] + ([self.video.on_tick] if self.video else [])
        self.robot = ContactRobot(self.world, watchers=watchers, on_restart=[self.scorer.reset])
        self.robot.show_plan = self.video.show_plan if self.video else None
        self.robot.plan_stats = self.video.plan_step if self.video else None

    def context(self, tags: frozenset[str], reasoner: ReasonerSettings, seed: int) -> ContactContext:
        """Only `oracle-physics` methods (the expert baselines, by design) are given the true physics and the seed;
        the others see object poses through the robot's camera unless `perception.poses=truth`."""
        self.robot.use_poses("truth" if ORACLE_TAG in tags else self.cfg.perception.poses)
        return self.task.context(self.cfg, self.setup, ORACLE_TAG in tags, reasoner, seed)

    def score(self) -> tuple[bool, TaskFigures]:
        success, figures = self.scorer.finish(self.world)
        return bool(success), figures

    @property
    def params(self) -> dict[str, Any]:
        return dict(self.setup.params)

    def outcome_text(self, success: bool, verdict: bool) -> str:
        return "ground truth: " + ("SUCCESS" if success else "FAILURE")


class ContactTask(Task):
    system = "contact"
    variants_help = "default (one variant; sizes, masses, frictions and poses are randomized by the condition)"
    default_variants = VARIANTS
    conditions = CONDITIONS
    default_method = "coral"
    contract_overrides = {"control.samples": 16, "control.episode_s": 2.5, "coral.max_attempts": 1}
    """What the task contract runs with: the real planner and physics on a short budget (16 samples,
    2.5 s of sim time: >1000 physics steps, the first stages' contacts; one attempt of a `coral`
    reference method) instead of whole trials."""
    method_tag = METHOD_TAG
    default_conditions = ("all",)
    """The paper's randomization (`random` draws the same)."""

    def __init__(self, spec: ContactTaskDef) -> None:
        self.spec = spec
        self.name = spec.name
        self.description = spec.description
        self.config_type = spec.config_type
        self.reference_method = spec.reference_method

    def setup(self, cfg: ContactConfig, condition: str, seed: int) -> TrialSetup:
        return self.spec.build(cfg, Drawer(condition, seed))

    def build(self, cfg: ContactConfig, condition: str, seed: int) -> tuple[EvaluationWorld, Scorer, TrialSetup]:
        """The trial's evaluation world (the truth) and its scorer."""
        setup = self.setup(cfg, condition, seed)
        world = EvaluationWorld(cfg, setup.scene, setup.truth)
        scorer = self.spec.scorer(cfg, setup)
        scorer.reset()
        return world, scorer, setup

    def context(self, cfg: ContactConfig, setup: TrialSetup, oracle: bool, reasoner: ReasonerSettings,
                seed: int) -> ContactContext:
        brief = TaskBrief(name=self.spec.name, instruction=self.spec.instruction, target=self.spec.target)
        if oracle:
            return ContactContext(cfg=cfg, task=brief, known=setup.scene, oracle_physics=dict(setup.truth),
                                  reasoner=reasoner, seed=seed)
        return ContactContext(cfg=withheld(cfg), task=brief, known=setup.scene, reasoner=reasoner)

    def episode(self, cfg: ContactConfig, variant: str, condition: str, seed: int,
                video: bool = False) -> ContactEpisode:
        return ContactEpisode(self, cfg, condition, seed, video)


def register(spec: ContactTaskDef) -> None:
    """Put one declared contact task in the task registry."""
    TASKS.register(spec.name, spec.description, tags=("system-c", "contact"))(lambda: ContactTask(spec))
