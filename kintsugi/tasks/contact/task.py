"""Runs any contact `ContactTaskDef`: spec -> evaluation world + robot + method -> scored TrialRecord.

A method must carry the `system-c` tag (it is given a `ContactContext` and a `ContactRobot`);
only methods also tagged `oracle-physics` get the trial's true masses and frictions in their
context. The scorer watches the evaluation world at the robot's inner rate and judges the end.
"""

from __future__ import annotations

import time
from typing import Callable

from kintsugi.config import apply_overrides
from kintsugi.errors import ConfigError, KintsugiError
from kintsugi.methods import METHODS
from kintsugi.tasks import TASKS
from kintsugi.tasks.contact.conditions import CONDITIONS, Drawer
from kintsugi.tasks.contact.config import ContactConfig
from kintsugi.tasks.contact.context import METHOD_TAG, ORACLE_TAG, ContactContext
from kintsugi.tasks.contact.robot import ContactRobot
from kintsugi.tasks.contact.spec import ContactTaskDef, Scorer, TrialSetup
from kintsugi.tasks.contact.world import EvaluationWorld
from kintsugi.trial import TrialLog, TrialRecord, TrialSpec

VARIANTS = ("default",)


class ContactTask:
    variants_help = "default (one variant; sizes, masses, frictions and poses are randomized by the condition)"
    default_variants = VARIANTS
    conditions = CONDITIONS
    reference_method = "expert-fsm"
    """The method that proves the task (contract tests run it)."""
    contract_overrides = {"control.samples": 16, "control.episode_s": 2.5}
    """What the task contract runs with: the real planner and physics on a short budget (16 samples,
    2.5 s of sim time: >1000 physics steps, the first stages' contacts) instead of whole trials."""
    method_tag = METHOD_TAG
    default_conditions = ("all",)
    """The paper's randomization (`random` draws the same)."""

    def __init__(self, spec: ContactTaskDef) -> None:
        self.spec = spec
        self.name = spec.name
        self.config_type = spec.config_type

    def config(self, overrides: dict | list) -> ContactConfig:
        return apply_overrides(self.spec.config_type(), overrides)

    def check_variant(self, name: str, config: ContactConfig | None = None) -> None:
        if name not in VARIANTS:
            raise ConfigError(f"unknown variant {name!r} for {self.name}; known: {', '.join(VARIANTS)}")

    def setup(self, cfg: ContactConfig, condition: str, seed: int) -> TrialSetup:
        return self.spec.build(cfg, Drawer(condition, seed))

    def build(self, cfg: ContactConfig, condition: str, seed: int) -> tuple[EvaluationWorld, Scorer, TrialSetup]:
        """The trial's evaluation world (the truth) and its scorer."""
        setup = self.setup(cfg, condition, seed)
        world = EvaluationWorld(cfg, setup.scene, setup.truth)
        scorer = self.spec.scorer(cfg, setup)
        scorer.reset()
        return world, scorer, setup

    def context(self, cfg: ContactConfig, setup: TrialSetup, oracle: bool, spec: TrialSpec) -> ContactContext:
        return ContactContext(cfg=cfg, task=self.spec, known=setup.scene, nominal=dict(setup.nominal),
                              oracle_physics=dict(setup.truth) if oracle else None, reasoner=spec.reasoner,
                              seed=spec.seed)

    def run(self, spec: TrialSpec, echo: Callable[[str], None] | None = None) -> TrialRecord:
        import kintsugi.methods.builtin  # noqa: F401 - registers the built-in methods

        start = time.perf_counter()
        cfg = self.config(spec.overrides)
        self.check_variant(spec.variant)
        entry = METHODS.get(spec.method)
        if METHOD_TAG not in entry.tags:
            fits = [e.name for e in METHODS if METHOD_TAG in e.tags]
            raise ConfigError(f"method {spec.method!r} does not run contact (system C) tasks such as {self.name}; "
                              f"methods that do: {', '.join(fits) or '(none)'}")
        world, scorer, setup = self.build(cfg, spec.condition, spec.seed)
        method = entry.factory(self.context(cfg, setup, ORACLE_TAG in entry.tags, spec))
        recorder = None
        if spec.video:
            from kintsugi.tasks.contact.video import ContactVideo

            recorder = ContactVideo(world)
        watchers = [scorer.watch] + ([recorder.on_tick] if recorder else [])
        robot = ContactRobot(world, watchers=watchers, on_restart=[scorer.reset])
        robot.show_plan = recorder.show_plan if recorder else None
        robot.plan_stats = recorder.plan_step if recorder else None
        log = TrialLog(echo=echo, on_status=recorder.status if recorder else None)
        error = None
        framework_success = False
        try:
            framework_success = bool(method.run(robot, log))
        except KintsugiError as exc:
            error = f"{type(exc).__name__}: {exc}"
            log.event(robot.sim_time, "error", error)
        success, details = scorer.finish(world)
        extra = getattr(method, "summary", lambda: {})()
        video = None
        if recorder is not None:
            recorder.finish("ground truth: " + ("SUCCESS" if success else "FAILURE"), success)
            video = str(recorder.save(spec.video)) if recorder.frames else None
            if video is not None and recorder.series.t:
                from kintsugi.tasks.contact.plot import plot_path_for, plot_plan

                plot = plot_plan(recorder.series, plot_path_for(video), title=spec.key)
                log.event(robot.sim_time, "plot", f"planner statistics: {plot}")
        world.close()
        return TrialRecord(
            key=spec.key, task=spec.task, method=spec.method, variant=spec.variant,
            condition=spec.condition, seed=spec.seed, params=dict(setup.params),
            success=bool(success), framework_success=framework_success and error is None,
            executions=dict(log.executions), skills=log.skills,
            events=sorted(log.events, key=lambda e: e.t), transitions=log.transitions,
            sim_time=round(robot.sim_time, 4), wall_time=time.perf_counter() - start,
            physics_steps=world.steps, error=error, video=video, transcript=log.transcript,
            details=details.model_dump(mode="json") | ({"method": extra} if extra else {}),
        )


def register(spec: ContactTaskDef) -> None:
    """Put one declared contact task in the task registry."""
    TASKS.register(spec.name, spec.description, tags=("system-c", "contact"))(lambda: ContactTask(spec))


def run_reference(task: ContactTask, condition: str, seed: int, overrides: dict | None = None) -> EvaluationWorld:
    """Build a trial's evaluation world and drive it with the reference method (no record); for checks
    that read MuJoCo's own counters after a realistic run."""
    from kintsugi.trial import ReasonerSettings

    spec = TrialSpec(task=task.name, method=task.reference_method, variant=VARIANTS[0], condition=condition,
                     seed=seed, overrides=overrides or {}, reasoner=ReasonerSettings())
    import kintsugi.methods.builtin  # noqa: F401

    cfg = task.config(spec.overrides)
    world, scorer, setup = task.build(cfg, condition, seed)
    entry = METHODS.get(spec.method)
    method = entry.factory(task.context(cfg, setup, ORACLE_TAG in entry.tags, spec))
    method.run(ContactRobot(world, watchers=[scorer.watch]), TrialLog())
    return world
