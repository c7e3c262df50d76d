"""Runs any tabletop `TaskSpec`: spec -> world + robot + method -> scored TrialRecord.

Each task file declares a spec; `register` puts it in the task registry. A method
must carry the `system-b` tag (it is given a `TabletopContext` and a `TabletopRobot`);
any other method is refused with a clear error before anything is built.
"""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from kintsugi.config import apply_overrides
from kintsugi.errors import ConfigError, KintsugiError
from kintsugi.methods import METHODS
from kintsugi.tasks import TASKS
from kintsugi.tasks.tabletop.conditions import CONDITIONS, DropDisturbance, TrialParams, sample_params
from kintsugi.tasks.tabletop.disturbances import Disturbances, KnockDisturbance, ShiftDisturbance
from kintsugi.tasks.tabletop.config import TabletopConfig
from kintsugi.tasks.tabletop.context import TabletopContext
from kintsugi.tasks.tabletop.robot import TabletopRobot
from kintsugi.tasks.tabletop.scene import CAMERAS
from kintsugi.tasks.tabletop.spec import Scorer, TaskSpec
from kintsugi.tasks.tabletop.suites import SUITES
from kintsugi.tasks.tabletop.world import TabletopWorld
from kintsugi.trial import TrialLog, TrialRecord, TrialSpec
from kintsugi.video import VideoRecorder

METHOD_TAG = "system-b"
VARIANTS = ("default",)


class _BothViews:
    """What the video recorder renders: the top and front views side by side."""

    def __init__(self, world: TabletopWorld) -> None:
        self.data = world.data
        self._world = world

    def render(self) -> np.ndarray:
        return np.hstack([self._world.render(c) for c in CAMERAS])


class TabletopTask:
    config_type = TabletopConfig
    variants_help = "default (one variant; the layout is randomized by the condition)"
    default_variants = VARIANTS
    reference_method = "scripted"
    """The method that proves the task (contract tests run it)."""
    method_tag = METHOD_TAG
    default_conditions = ("none", "pose", "drop")
    suites = SUITES
    """Named campaigns (`kintsugi bench <task> --suite table1`): AgentChord's Table I cells."""

    def __init__(self, spec: TaskSpec) -> None:
        self.spec = spec
        self.name = spec.name
        missing = {"shift": spec.shift, "knock": spec.knock}
        self.conditions = {k: v for k, v in CONDITIONS.items() if k not in missing or missing[k] is not None}
        """`shift` / `knock` only where the task names an object for them."""

    def config(self, overrides: dict | list) -> TabletopConfig:
        return apply_overrides(TabletopConfig(), overrides)

    def check_variant(self, name: str, config: TabletopConfig | None = None) -> None:
        if name not in VARIANTS:
            raise ConfigError(f"unknown variant {name!r} for {self.name}; known: {', '.join(VARIANTS)}")

    def build(self, cfg: TabletopConfig, condition: str, seed: int
              ) -> tuple[TabletopWorld, Scorer, Disturbances | None, TrialParams]:
        """The trial's world with its scorer and disturbances watching every control tick."""
        self._check_targets(cfg)
        params = sample_params(cfg, self.spec.objects, condition, seed, known=self.conditions)
        world = TabletopWorld(cfg, self.spec.objects, params.start, self.spec.targets)
        scorer = self.spec.scorer(cfg)
        world.watchers.append(scorer.watch)
        parts: list = []
        if params.drop_p > 0:
            parts.append(DropDisturbance(world, params.drop_p, cfg.disturbance.drop_release_s, seed))
        if params.shift and self.spec.shift is not None:
            parts.append(ShiftDisturbance(world, *self.spec.shift, cfg.disturbance, seed))
        if params.knock and self.spec.knock is not None:
            parts.append(KnockDisturbance(world, *self.spec.knock, cfg.disturbance, seed))
        hook = Disturbances(parts) if parts else None
        if hook is not None:
            world.watchers.append(hook)
        return world, scorer, hook, params

    def _check_targets(self, cfg: TabletopConfig) -> None:
        for name in self.spec.targets:
            if name not in cfg.targets:
                raise ConfigError(f"targets.{name} is missing: task {self.name} needs it; "
                                  f"configured: {', '.join(cfg.targets)}")
            rel = cfg.targets[name].relative_to
            if rel is not None and rel not in self.spec.objects:
                raise ConfigError(f"targets.{name}.relative_to is {rel!r}, which is not in task {self.name}; "
                                  f"its objects: {', '.join(self.spec.objects)}")

    def run(self, spec: TrialSpec, echo: Callable[[str], None] | None = None,
            attach: Callable[[TabletopRobot, TrialLog], None] | None = None) -> TrialRecord:
        """`attach` (optional) is given the robot and the trial log before the method starts: an outside
        observer such as the trajectory exporter adds its step observer there; it must not act."""
        import kintsugi.methods.builtin  # noqa: F401 - registers the built-in methods

        start = time.perf_counter()
        cfg = self.config(spec.overrides)
        self.check_variant(spec.variant)
        entry = METHODS.get(spec.method)
        if METHOD_TAG not in entry.tags:
            fits = [e.name for e in METHODS if METHOD_TAG in e.tags]
            raise ConfigError(f"method {spec.method!r} does not run tabletop (system B) tasks such as {self.name}; "
                              f"methods that do: {', '.join(fits) or '(none)'}")
        method = entry.factory(TabletopContext(cfg=cfg, task=self.spec, reasoner=spec.reasoner))
        world, scorer, drop, params = self.build(cfg, spec.condition, spec.seed)
        recorder = VideoRecorder(scale=1) if spec.video else None
        view = _BothViews(world)
        robot = TabletopRobot(world, hook=drop, on_tick=(lambda: recorder.on_tick(view)) if recorder else None)

        def on_status(label: str, verdict: str | None) -> None:
            if recorder is not None:
                recorder.label = label
                if verdict is not None:
                    recorder.verdict = verdict

        log = TrialLog(echo=echo, on_status=on_status)
        if attach is not None:
            attach(robot, log)
        error = None
        framework_success = False
        try:
            framework_success = bool(method.run(robot, log))
        except KintsugiError as exc:
            error = f"{type(exc).__name__}: {exc}"
            log.event(robot.sim_time, "error", error)
        for t, what in drop.events if drop else []:
            log.event(t, "disturbance", what)
        success, details = scorer.finish(world)
        video = str(recorder.save(spec.video)) if recorder is not None and recorder.frames else None
        world.close()
        calls = log.transcript
        return TrialRecord(
            key=spec.key, task=spec.task, method=spec.method, variant=spec.variant,
            condition=spec.condition, seed=spec.seed, params=params.flat(),
            success=success, framework_success=framework_success and error is None,
            executions=dict(log.executions), skills=log.skills,
            events=sorted(log.events, key=lambda e: e.t), transitions=log.transitions,
            sim_time=round(robot.sim_time, 4), wall_time=time.perf_counter() - start,
            physics_steps=world.steps, reasoning_calls=len(calls),
            reasoning_latency_s=sum(c.get("latency_s", 0.0) for c in calls),
            reasoning_errors=sum(1 for c in calls if c.get("error")),
            transcript=calls, error=error, video=video, details=details.model_dump(mode="json"),
        )


def expand(entry: object, robot: TabletopRobot) -> list:
    """A script entry as actions: a dict is one action; a callable (a step whose targets depend on
    where things are by then, e.g. a cloth the grasp dragged) is given a fresh observation."""
    if callable(entry):
        out = entry(robot.observation(images=False))
        return out if isinstance(out, list) else [out]
    return [entry]


def run_script(task: TabletopTask, condition: str, seed: int, overrides: dict | None = None) -> TabletopWorld:
    """Build a trial's world and run the task's scripted sequence on it (no method, no record)."""
    world, _, drop, _ = task.build(task.config(overrides or {}), condition, seed)
    robot = TabletopRobot(world, hook=drop)
    for entry in task.spec.script(robot.observation(images=False)):
        for action in expand(entry, robot):
            robot.execute(action)
    return world


def register(spec: TaskSpec) -> None:
    """Put one declared tabletop task in the task registry."""
    TASKS.register(spec.name, spec.description, tags=("system-b", "tabletop"))(lambda: TabletopTask(spec))
