"""A campaign's config and its expansion into trials.

Trial i of every (method, variant, condition) cell uses seed base_seed + i, so
every method meets the same randomized conditions: comparisons are paired.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import Field, ValidationError, field_validator

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError
from kintsugi.core.record import ReasonerSettings, TrialSpec

# Fields that may change between runs into the same out dir: the trial count may
# grow (or shrink), and which trials record videos does not change any outcome.
RESUMABLE_FIELDS = frozenset({"trials", "videos_per_cell"})


class CampaignConfig(StrictModel):
    """Everything that defines a campaign's trials; unknown keys are rejected."""

    task: str
    methods: list[str] = Field(min_length=1)
    variants: list[str] = Field(min_length=1)
    conditions: list[str] = Field(min_length=1)
    trials: int = Field(default=30, ge=1, description="trials per (method, variant, condition) cell")
    base_seed: int = Field(default=0, ge=0)
    overrides: dict[str, Any] = Field(default_factory=dict)
    reasoner: ReasonerSettings = ReasonerSettings()
    plugins: list[str] = Field(
        default_factory=list,
        description="modules imported in every worker before running, so third-party tasks register",
    )
    videos_per_cell: int = Field(default=0, ge=0, description="record a video of the first N trials of each cell")

    @field_validator("task")
    @classmethod
    def _task_name(cls, v: str) -> str:
        _check_name(v, "task")
        return v

    @field_validator("methods", "variants", "conditions")
    @classmethod
    def _names(cls, v: list[str], info: Any) -> list[str]:
        for name in v:
            _check_name(name, info.field_name)
        dupes = sorted({n for n in v if v.count(n) > 1})
        if dupes:
            raise ValueError(f"{info.field_name} lists {', '.join(dupes)} more than once")
        return v

    def cells(self) -> list[tuple[str, str, str]]:
        """(method, variant, condition) in config order: methods outermost."""
        return [(m, v, c) for m in self.methods for v in self.variants for c in self.conditions]

    def seeds(self) -> list[int]:
        return [self.base_seed + i for i in range(self.trials)]


def _check_name(name: str, what: str) -> None:
    # Names go into trial keys "task/method/variant/condition/seed" and file names.
    if not name or "/" in name or name != name.strip():
        raise ValueError(f"{what} name {name!r} must be non-empty, without '/' or surrounding spaces")


def build_config(**fields: Any) -> CampaignConfig:
    """A CampaignConfig from user input (the CLI's `run` and `bench`), fully validated before any trial.

    Names are looked up before the format rules run, so `peg[/x]` reads "unknown task", and every
    problem is a one-line KintsugiError rather than a pydantic traceback.
    """
    validate(CampaignConfig.model_construct(**fields))
    try:
        return CampaignConfig(**fields)
    except ValidationError as exc:
        problems = "; ".join(f"{'.'.join(str(p) for p in e['loc']) or 'config'}: {e['msg']}" for e in exc.errors())
        raise ConfigError(f"bad campaign setting: {problems}") from None


def validate(cfg: CampaignConfig) -> None:
    """Check every name and setting a campaign uses, so a typo fails before the first trial, not in every one.

    In order: task and plugins, methods (each must drive the task's robot), `--set` overrides
    against the task's typed config and `method.*` / `methods.<name>.*` ones against each method's, variants,
    conditions, the reasoner backend and its settings (building it checks e.g. that the openai
    backend has a key or a base URL).
    """
    from kintsugi.campaign.bootstrap import bootstrap
    from kintsugi.core.registry import TASKS
    from kintsugi.core.resolve import check_scoped, method_for, reasoner_settings, split_overrides
    from kintsugi.reasoning import make_reasoner

    bootstrap(cfg.plugins, cfg.task)
    task = TASKS.get(cfg.task).factory()
    check_scoped(cfg.overrides, cfg.methods)
    for name in cfg.methods:
        method_for(task, name).configure(split_overrides(cfg.overrides, name)[1])
    task_overrides, _, reasoner_overrides = split_overrides(cfg.overrides)
    config = task.config(task_overrides)
    for name in cfg.variants:
        task.check_variant(name, config)
    _known(cfg.conditions, task.conditions, f"condition for task {cfg.task!r}")
    make_reasoner(reasoner_settings(cfg.reasoner, reasoner_overrides))


def task_defaults(task: str, plugins: list[str] | tuple[str, ...] = ()) -> tuple[str, str, tuple[str, ...]]:
    """What `run` and `bench` use when no method, variant or condition is given: the task's own.

    (the system's own method, first default variant, default conditions), so that e.g. `kintsugi run
    pour-single` runs `agentchord` on `default` instead of the peg task's names.
    """
    from kintsugi.campaign.bootstrap import bootstrap
    from kintsugi.core.registry import TASKS

    bootstrap(plugins, task)
    made = TASKS.get(task).factory()
    conditions = getattr(made, "conditions", None) or ("none",)
    return (getattr(made, "default_method", None) or getattr(made, "reference_method", "baseline"),
            next(iter(getattr(made, "default_variants", ("default",)))),
            tuple(getattr(made, "default_conditions", None) or conditions))


DEFAULT_TRIALS = 30
"""Trials per cell when neither the command nor a suite names a count."""


def campaign_for(task: str, methods: list[str] | None = None, variants: list[str] | None = None,
                 conditions: list[str] | None = None, trials: int | None = None, suite: str | None = None,
                 **fields: Any) -> CampaignConfig:
    """A validated campaign with the defaults `kintsugi bench`, `kintsugi run` and `kintsugi.bench` share.

    What is not given comes from the named `suite` (its overrides go under `fields["overrides"]`), else from
    the task: its own system's method, its first variant, its default conditions, `DEFAULT_TRIALS`."""
    plugins = list(fields.pop("plugins", None) or [])
    named = suite_of(task, suite, plugins) if suite else None
    method, variant, default_conditions = task_defaults(task, plugins)
    overrides = (dict(named.overrides) if named else {}) | dict(fields.pop("overrides", None) or {})
    return build_config(
        task=task,
        methods=list(methods) if methods else list(named.methods) if named else [method],
        variants=list(variants) if variants else list(named.shapes) if named else [variant],
        conditions=list(conditions) if conditions else list(named.conditions) if named else list(default_conditions),
        trials=trials or (named.trials if named else DEFAULT_TRIALS), overrides=overrides, plugins=plugins,
        **fields)


def suite_of(task: str, name: str, plugins: list[str] | tuple[str, ...] = ()) -> Any:
    """A task's named campaign (methods, variants, conditions, trials, overrides, companion).

    A task offers suites through a `suites` mapping; asking one that has none is a clear error.
    """
    from kintsugi.campaign.bootstrap import bootstrap
    from kintsugi.core.registry import TASKS

    bootstrap(plugins, task)
    suites = getattr(TASKS.get(task).factory(), "suites", None) or {}
    if name not in suites:
        known = ", ".join(suites) if suites else "none (this task has no named suites)"
        raise ConfigError(f"unknown suite {name!r} for task {task!r}; known: {known}")
    return suites[name]


def _known(names: list[str], known: Any, what: str) -> None:
    for name in names:
        if name not in known:
            raise ConfigError(f"unknown {what}: {name!r}; known: {', '.join(known)}")


def video_path(video_dir: Path, key: str) -> Path:
    """Where a trial's video goes: one file per key, '/' replaced so it is a flat file name."""
    return video_dir / (key.replace("/", "__") + ".mp4")


def expand(cfg: CampaignConfig, video_dir: Path | None = None) -> list[TrialSpec]:
    """All trials of the campaign, cell by cell in config order, seeds base_seed + i."""
    specs: list[TrialSpec] = []
    for method, variant, condition in cfg.cells():
        for i, seed in enumerate(cfg.seeds()):
            spec = TrialSpec(
                task=cfg.task,
                method=method,
                variant=variant,
                condition=condition,
                seed=seed,
                overrides=cfg.overrides,
                reasoner=cfg.reasoner,
            )
            if video_dir is not None and i < cfg.videos_per_cell:
                spec = spec.model_copy(update={"video": str(video_path(video_dir, spec.key))})
            specs.append(spec)
    return specs
