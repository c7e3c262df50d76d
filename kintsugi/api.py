"""The Python API: one trial, one campaign and a task's default settings, with the command line's defaults.

    import kintsugi
    rec = kintsugi.run("pour-single", method="agentchord", condition="drop", seed=3)
    records = kintsugi.bench("peg-insertion", methods=["baseline", "recovery"], trials=5, out="runs/api")

A bad name or setting raises `kintsugi.ConfigError` (a `KintsugiError`) naming it, before anything runs.
A trial that fails while running (an unreachable endpoint, a refused plan) is a record with `error` set,
as on the command line.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

from kintsugi.campaign.plan import CampaignConfig, campaign_for, expand, task_defaults
from kintsugi.core.errors import ConfigError, KintsugiError, UnknownNameError
from kintsugi.core.record import ReasonerSettings, TrialRecord
from kintsugi.core.resolve import load_settings_file, settings_document

__all__ = ["ConfigError", "KintsugiError", "bench", "campaign", "default_config", "run"]


def _overrides(overrides: dict[str, Any] | None, config: str | Path | None) -> dict[str, Any]:
    base = load_settings_file(config) if config is not None else {}
    if overrides is not None and not isinstance(overrides, dict):
        raise ConfigError(f"overrides must be a dict of dotted keys to values, not {type(overrides).__name__}")
    return base | dict(overrides or {})


def _reasoner(reasoner: str | ReasonerSettings, **fields: Any) -> ReasonerSettings:
    if isinstance(reasoner, ReasonerSettings):
        return reasoner
    return ReasonerSettings(backend=reasoner, **{k: v for k, v in fields.items() if v is not None})


def campaign(task: str, methods: Iterable[str] | None = None, variants: Iterable[str] | None = None,
             conditions: Iterable[str] | None = None, trials: int | None = None, *, suite: str | None = None,
             base_seed: int = 0, overrides: dict[str, Any] | None = None, config: str | Path | None = None,
             reasoner: str | ReasonerSettings = "embedded", model: str | None = None,
             base_url: str | None = None, plugins: Iterable[str] = (), videos_per_cell: int = 0) -> CampaignConfig:
    """The validated campaign `bench` would run (the same defaults as `kintsugi bench`); a bad name or setting
    raises ConfigError."""
    try:
        return _campaign(task, methods, variants, conditions, trials, suite, base_seed, overrides, config,
                         reasoner, model, base_url, plugins, videos_per_cell)
    except UnknownNameError as exc:  # an unknown task, method or backend is a bad setting here
        raise ConfigError(str(exc)) from None


def _campaign(task, methods, variants, conditions, trials, suite, base_seed, overrides, config,  # noqa: ANN001, ANN202, PLR0913
              reasoner, model, base_url, plugins, videos_per_cell):
    return campaign_for(task, list(methods) if methods else None, list(variants) if variants else None,
                        list(conditions) if conditions else None, trials, suite, base_seed=base_seed,
                        overrides=_overrides(overrides, config), plugins=list(plugins),
                        reasoner=_reasoner(reasoner, model=model, base_url=base_url),
                        videos_per_cell=videos_per_cell)


def run(task: str, method: str | None = None, variant: str | None = None, condition: str | None = None,
        seed: int = 0, *, overrides: dict[str, Any] | None = None, config: str | Path | None = None,
        reasoner: str | ReasonerSettings = "embedded", model: str | None = None, base_url: str | None = None,
        video: str | Path | None = None, plugins: Iterable[str] = (), echo: Any = None) -> TrialRecord:
    """Run one trial and return its record; defaults as `kintsugi run` (the task's own system's method, its
    first variant and first default condition). `echo(line)` receives the trial's story, if given."""
    from kintsugi.core.runner import run_trial
    from kintsugi.core.video import check_video_path

    plugins = list(plugins)
    conditions = [condition] if condition else [task_defaults(task, plugins)[2][0]]
    cfg = campaign(task, [method] if method else None, [variant] if variant else None, conditions, 1,
                   base_seed=seed, overrides=overrides, config=config, reasoner=reasoner, model=model,
                   base_url=base_url, plugins=plugins)
    spec = expand(cfg)[0]
    if video is not None:
        spec = spec.model_copy(update={"video": str(check_video_path(Path(video)))})
    return run_trial(spec, echo=echo)


def bench(task: str, methods: Iterable[str] | None = None, variants: Iterable[str] | None = None,
          conditions: Iterable[str] | None = None, trials: int | None = None, *, out: str | Path | None = None,
          workers: int = 2, executor: str = "process", report: bool = True, progress: bool = False,
          trial_timeout_s: float | None = 3600.0, **fields: Any) -> list[TrialRecord]:
    """Run (or resume) a campaign into `out` (default runs/campaign, or runs/<suite>) and return its records
    in config order; `report=True` also writes report.md, report.html and the trial pages. Other keyword
    arguments as for `campaign`."""
    from kintsugi.campaign.report import write_report
    from kintsugi.campaign.runner import run_campaign

    cfg = campaign(task, methods, variants, conditions, trials, **fields)
    where = Path(out) if out is not None else Path("runs") / (fields.get("suite") or "campaign")
    records = run_campaign(cfg, where, workers=workers, executor=executor, progress=progress,
                           trial_timeout_s=trial_timeout_s)
    if report:
        write_report(where, cfg, records)
    return records


def default_config(task: str, method: str | None = None, overrides: dict[str, Any] | None = None,
                   plugins: Iterable[str] = ()) -> dict[str, Any]:
    """Every setting of `task` and of `method` (default: the task's own system's method) as printed by
    `kintsugi config`: `{"task": {...}, "methods": {method: {...}}}`; save it as YAML for `config=`."""
    plugins = list(plugins)
    try:
        return settings_document(task, method or task_defaults(task, plugins)[0], _overrides(overrides, None))
    except UnknownNameError as exc:
        raise ConfigError(str(exc)) from None
