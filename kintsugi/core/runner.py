"""The one runner: task x method x variant x condition x seed -> one TrialRecord.

Every system's trials pass through `run_trial`: it resolves the names, builds the task's episode
and the method (with its typed config), runs the method on the episode's robot, scores the
episode, closes the video and assembles the record. Reasoning calls, latency and errors are
counted here from the transcript, the same way for every system. A failure inside the trial (an
exception, diverging physics, a bad model reply) becomes the record's `error`, never a lost trial.
"""

from __future__ import annotations

import time
import traceback
from typing import Any, Callable

from pydantic import ValidationError

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError, KintsugiError
from kintsugi.core.log import TrialLog
from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import Event, ReasonerSettings, TrialRecord, TrialSpec
from kintsugi.core.registry import METHODS, REASONERS, TASKS

Echo = Callable[[str], None]
Attach = Callable[[Any, TrialLog], None]


def split_overrides(overrides: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(task, method, reasoner) overrides: `method.<key>` go to the method's config, `reasoner.<key>` to the
    reasoner settings (`reasoner_settings`), every other key to the task's."""
    method = {k.split(".", 1)[1]: v for k, v in overrides.items() if k.startswith("method.")}
    reasoner = {k.split(".", 1)[1]: v for k, v in overrides.items() if k.startswith("reasoner.")}
    task = {k: v for k, v in overrides.items() if not k.startswith(("method.", "reasoner."))}
    return task, method, reasoner


def resolve(spec: TrialSpec) -> tuple[Any, Any, Any, Any, Any]:
    """(task, method entry, task config, method config, reasoner settings) for a spec; ConfigError names
    what is wrong."""
    load_builtins()
    task = TASKS.get(spec.task).factory()
    entry = METHODS.get(spec.method)
    if task.method_tag not in entry.tags:
        fits = [e.name for e in METHODS if task.method_tag in e.tags]
        raise ConfigError(f"method {spec.method!r} does not run {task.name} (it drives another robot); "
                          f"methods that do: {', '.join(fits) or '(none)'}")
    task_overrides, method_overrides, reasoner_overrides = split_overrides(spec.overrides)
    cfg = task.config(task_overrides)
    task.check_variant(spec.variant, cfg)
    return task, entry, cfg, entry.configure(method_overrides), reasoner_settings(spec.reasoner, reasoner_overrides)


def backend_options(entry: Any, options: dict[str, Any]) -> Any:
    """A reasoner backend's `options` validated by its settings class; ConfigError names
    `reasoner.options.<key>`."""
    try:
        return entry.config.model_validate(dict(options))
    except ValidationError as exc:
        known = ", ".join(entry.config.model_fields) or "none"
        problems = []
        for err in exc.errors(include_url=False, include_input=False):
            key = ".".join(["reasoner.options", *(str(p) for p in err["loc"])])
            if err["type"] == "extra_forbidden":
                problems.append(f"unknown key {key!r} (the {entry.name} backend's options: {known})")
            else:
                problems.append(f"{key}: {err['msg']}")
        raise ConfigError(f"bad reasoner option: {'; '.join(problems)}") from None


def reasoner_settings(settings: ReasonerSettings, overrides: dict[str, Any]) -> ReasonerSettings:
    """`settings` with `reasoner.*` overrides applied (keys without the prefix: `model`, `options.replies`),
    checked: the backend must be registered and its options pass its settings class. Errors are one
    line naming the key."""
    options = dict(settings.options)
    common: dict[str, Any] = {}
    for key, value in overrides.items():
        if key == "options":
            if not isinstance(value, dict):
                raise ConfigError(f"reasoner.options must be a JSON object of the backend's options, not {value!r}")
            options |= value
        elif key.startswith("options."):
            options[key.removeprefix("options.")] = value
        else:
            common[key] = value
    out = apply_overrides(settings, common, prefix="reasoner") if common else settings
    out = out.model_copy(update={"options": options})
    load_builtins()
    backend_options(REASONERS.get(out.backend), options)
    return out


def run_trial(spec: TrialSpec, echo: Echo | None = None, attach: Attach | None = None) -> TrialRecord:
    """Run one trial; any exception becomes a recorded failed trial, never a lost one.

    `echo` tells the story live; `attach` (optional) is given the robot and the log before the method
    starts: an outside observer such as the trajectory exporter hooks in there, and must not act.
    """
    start = time.perf_counter()
    try:
        record = _run(spec, echo, attach)
    except Exception as exc:  # noqa: BLE001 - a campaign must survive any trial failure
        record = failed_record(spec, f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=4)}")
    return record.model_copy(update={"wall_time": time.perf_counter() - start})


def failed_record(spec: TrialSpec, error: str) -> TrialRecord:
    """The record of a trial that could not run (or whose worker died): a failure with its reason."""
    return TrialRecord(key=spec.key, task=spec.task, method=spec.method, variant=spec.variant,
                       condition=spec.condition, seed=spec.seed, error=error)


def _run(spec: TrialSpec, echo: Echo | None, attach: Attach | None) -> TrialRecord:
    task, entry, cfg, method_cfg, reasoner = resolve(spec)
    episode = task.episode(cfg, spec.variant, spec.condition, spec.seed, video=bool(spec.video))
    try:
        method = entry.factory(episode.context(entry.tags, reasoner, spec.seed), method_cfg)
        video = episode.video
        log = TrialLog(echo=echo, on_status=video.status if video is not None else None)
        if attach is not None:
            attach(episode.robot, log)
        error = None
        verdict = False
        try:
            verdict = bool(method.run(episode.robot, log))
        except KintsugiError as exc:
            error = f"{type(exc).__name__}: {exc}"
            log.event(episode.sim_time, "error", error)
        for t, what in episode.disturbances():
            log.event(t, "disturbance", what)
        success, figures = episode.score()
        verdict = verdict and error is None
        saved = None
        if video is not None and video.frames:
            video.finish(episode.outcome_text(success, verdict), success)  # scored: the video may show truth now
            saved = video.save(spec.video)
            for kind, detail in getattr(video, "notes", ()):
                log.event(episode.sim_time, kind, detail)
        return _record(spec, episode, log, success, verdict, figures, error, saved)
    finally:
        episode.close()


def _record(spec: TrialSpec, episode: Any, log: TrialLog, success: bool, verdict: bool, figures: Any,
            error: str | None, video: str | None) -> TrialRecord:
    calls = log.transcript
    return TrialRecord(
        key=spec.key, task=spec.task, method=spec.method, variant=spec.variant,
        condition=spec.condition, seed=spec.seed, params=episode.params,
        success=bool(success), framework_success=verdict,
        executions=dict(log.executions), transitions=log.transitions, skills=log.skills,
        events=sorted(log.events, key=lambda e: e.t),
        sim_time=round(episode.sim_time, 4), physics_steps=episode.physics_steps,
        reasoning_calls=len(calls), reasoning_latency_s=sum(c.get("latency_s", 0.0) for c in calls),
        reasoning_errors=sum(1 for c in calls if c.get("error")), transcript=calls, error=error,
        video=str(video) if video else None,
        task_figures=figures.model_dump(mode="json") if figures is not None else {},
        method_figures=log.method_figures.model_dump(mode="json") if log.method_figures is not None else {},
    )


__all__ = ["Event", "backend_options", "failed_record", "reasoner_settings", "resolve", "run_trial",
           "split_overrides"]
