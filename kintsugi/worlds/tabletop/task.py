"""Any tabletop `TaskSpec` as a task: a trial's world, disturbances, robot and scorer as an `Episode`.

Each task file declares a spec; `register` puts it in the task registry. Methods tagged
`system-b` drive it: they get a `TabletopContext` and a `TabletopRobot`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.core.record import ReasonerSettings, TaskFigures
from kintsugi.core.registry import TASKS
from kintsugi.core.task import Episode, Task
from kintsugi.worlds.tabletop.conditions import CONDITIONS, DropDisturbance, TrialParams, sample_params
from kintsugi.worlds.tabletop.disturbances import Disturbances, KnockDisturbance, ShiftDisturbance
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.context import TabletopContext
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.scene import CAMERAS
from kintsugi.worlds.tabletop.spec import Scorer, TaskSpec
from kintsugi.worlds.tabletop.suites import SUITES
from kintsugi.worlds.tabletop.world import TabletopWorld
from kintsugi.core.video import VideoRecorder

METHOD_TAG = "system-b"
VARIANTS = ("default",)


class _BothViews:
    """What the video recorder renders: the top and front views side by side."""

    def __init__(self, world: TabletopWorld) -> None:
        self.data = world.data
        self._world = world

    def render(self) -> np.ndarray:
        return np.hstack([self._world.render(c) for c in CAMERAS])


class TabletopEpisode(Episode):
    def __init__(self, task: "TabletopTask", cfg: TabletopConfig, condition: str, seed: int, video: bool) -> None:
        self.task, self.cfg = task, cfg
        self.world, self.scorer, self.hook, self._params = task.build(cfg, condition, seed)
        self.video = VideoRecorder(scale=1) if video else None
        view = _BothViews(self.world)
        self.robot = TabletopRobot(self.world, hook=self.hook,
                                   on_tick=(lambda: self.video.on_tick(view)) if self.video else None)

    def context(self, tags: frozenset[str], reasoner: ReasonerSettings, seed: int) -> TabletopContext:
        return TabletopContext(cfg=self.cfg, task=self.task.spec, reasoner=reasoner)

    def score(self) -> tuple[bool, TaskFigures]:
        return self.scorer.finish(self.world)

    def disturbances(self) -> list[tuple[float, str]]:
        return list(self.hook.events) if self.hook else []

    @property
    def params(self) -> dict[str, Any]:
        return self._params.flat()


class TabletopTask(Task):
    config_type = TabletopConfig
    system = "tabletop"
    variants_help = "default (one variant; the layout is randomized by the condition)"
    default_variants = VARIANTS
    reference_method = "scripted"
    default_method = "agentchord"
    method_tag = METHOD_TAG
    default_conditions = ("none", "pose", "drop")
    suites = SUITES
    """Named campaigns (`kintsugi bench <task> --suite table1`): AgentChord's Table I cells."""

    def __init__(self, spec: TaskSpec) -> None:
        self.spec = spec
        self.name = spec.name
        self.description = spec.description
        self.config_type = task_config_type(spec, type(self).config_type)
        """The task's own config: the shared sections plus the objects and regions its spec declares."""
        missing = {"shift": spec.shift, "knock": spec.knock}
        self.conditions = {k: v for k, v in CONDITIONS.items() if k not in missing or missing[k] is not None}
        """`shift` / `knock` only where the task names an object for them."""

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

    def episode(self, cfg: TabletopConfig, variant: str, condition: str, seed: int,
                video: bool = False) -> TabletopEpisode:
        return TabletopEpisode(self, cfg, condition, seed, video)


def task_config_type(spec: TaskSpec, base: type[TabletopConfig] = TabletopConfig) -> type[TabletopConfig]:
    """`base` with the spec's declared objects and regions as defaults of its `objects` and `targets`
    sections (the same class for the same spec: records and workers rebuild it by name). A declared name
    that clashes with a built-in object, or an object in `objects` that is neither built in nor declared,
    is a ConfigError naming it."""
    from pydantic import create_model

    from kintsugi.worlds.tabletop.config import ObjectSection, ObjectsSection, Region
    from kintsugi.worlds.tabletop.objects import BUILT_IN

    clash = sorted(set(spec.declared) & set(ObjectsSection.model_fields))
    if clash:
        raise ConfigError(f"task {spec.name}: declared object {clash[0]!r} is a built-in object's name; rename it")
    unknown = [o for o in spec.objects if o not in spec.declared and o not in BUILT_IN]
    if unknown:
        raise ConfigError(f"task {spec.name}: object {unknown[0]!r} is neither built in ({', '.join(BUILT_IN)}) "
                          "nor declared in TaskSpec.declared")
    stray = sorted(set(spec.declared) - set(spec.objects))
    if stray:
        raise ConfigError(f"task {spec.name}: declared object {stray[0]!r} is not in TaskSpec.objects")
    if not spec.declared and not spec.regions:
        return base
    stem = "".join(p.capitalize() for p in spec.name.replace("-", "_").split("_"))
    cached = globals().get(f"{stem}Config")
    if cached is not None and getattr(cached, "_spec_name", None) == spec.name:
        return cached
    objects = create_model(f"{stem}Objects", __base__=ObjectsSection, __module__=__name__,
                           **{n: (ObjectSection, o) for n, o in spec.declared.items()})
    targets = {**base.model_fields["targets"].default, **spec.regions}
    cfg = create_model(f"{stem}Config", __base__=base, __module__=__name__,
                       objects=(objects, objects()), targets=(dict[str, Region], targets))
    cfg._spec_name = spec.name
    globals()[objects.__name__], globals()[cfg.__name__] = objects, cfg  # picklable by name
    return cfg


def expand(entry: object, robot: TabletopRobot) -> list:
    """A script entry as actions: a dict is one action; a callable (a step whose targets depend on
    where things are by then, e.g. a cloth the grasp dragged) is given a fresh observation."""
    if callable(entry):
        out = entry(robot.observation(images=False))
        return out if isinstance(out, list) else [out]
    return [entry]


def register(spec: TaskSpec, task_type: type[TabletopTask] = TabletopTask) -> None:
    """Put one declared tabletop task in the task registry."""
    TASKS.register(spec.name, spec.description, tags=("system-b", "tabletop"))(lambda: task_type(spec))
