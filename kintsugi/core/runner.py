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

from kintsugi.core.errors import KintsugiError
from kintsugi.core.log import TrialLog
from kintsugi.core.record import TrialRecord, TrialSpec
from kintsugi.core.resolve import resolve

Echo = Callable[[str], None]
Attach = Callable[[Any, TrialLog], None]


def run_trial(spec: TrialSpec, echo: Echo | None = None, attach: Attach | None = None) -> TrialRecord:
    """Run one trial; any exception becomes a recorded failed trial, never a lost one.

    `echo` tells the story live; `attach` (optional) is given the robot and the log before the method
    starts: an outside observer such as the trajectory exporter hooks in there, and must not act.
    """
    start = time.perf_counter()
    try:
        record = _run(spec, echo, attach, start)
    except Exception as exc:  # noqa: BLE001 - a campaign must survive any trial failure
        record = failed_record(spec, f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=4)}")
    return record.model_copy(update={"wall_time": time.perf_counter() - start})


def failed_record(spec: TrialSpec, error: str) -> TrialRecord:
    """The record of a trial that could not run (or whose worker died): a failure with its reason."""
    return TrialRecord(**spec.identity(), error=error)


def _run(spec: TrialSpec, echo: Echo | None, attach: Attach | None, started: float) -> TrialRecord:
    task, entry, cfg, method_cfg, reasoner = resolve(spec)
    episode = task.episode(cfg, spec.variant, spec.condition, spec.seed, video=bool(spec.video))
    try:
        method = entry.factory(episode.context(entry.tags, reasoner, spec.seed), method_cfg)
        video = episode.video
        log = TrialLog(echo=echo, on_status=video.status if video is not None else None, started=started)
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
            try:
                saved = video.save(spec.video)
            except KintsugiError as exc:  # the trial ran and was scored: keep it, say what went wrong
                log.event(episode.sim_time, "video", f"not saved: {exc}")
            for kind, detail in getattr(video, "notes", ()):
                log.event(episode.sim_time, kind, detail)
        return _record(spec, episode, log, success, verdict, figures, error, saved)
    finally:
        episode.close()


def _record(spec: TrialSpec, episode: Any, log: TrialLog, success: bool, verdict: bool, figures: Any,
            error: str | None, video: str | None) -> TrialRecord:
    calls = log.transcript
    return TrialRecord(
        **spec.identity(), params=episode.params,
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


__all__ = ["failed_record", "run_trial"]
