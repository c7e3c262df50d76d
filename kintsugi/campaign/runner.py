"""Run a campaign: expand, skip what results.jsonl already holds, run the rest, append as they finish.

Resume is by trial key: kill the process at any moment and rerun the same
command; every trial whose line reached the disk is skipped, every other one runs.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from kintsugi.campaign.executors import failed_record, make_executor
from kintsugi.campaign.plan import CampaignConfig, expand, validate
from kintsugi.campaign.store import ResultStore
from kintsugi.core.record import TrialRecord, TrialSpec
from kintsugi.reasoning.preflight import prepare


def _progress(console: Console, enabled: bool) -> Progress:
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("[green]{task.fields[ok]} ok[/] [red]{task.fields[err]} errors[/]"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        console=console,
        disable=not enabled,
    )


def run_campaign(
    cfg: CampaignConfig,
    out_dir: str | Path,
    workers: int = 2,
    executor: str = "process",
    progress: bool = True,
    console: Console | None = None,
    trial_timeout_s: float | None = None,
) -> list[TrialRecord]:
    """Run (or resume) a campaign into `out_dir`; return the records of all its trials, in config order.

    Raises KintsugiError before running anything if any name or setting is wrong
    (`plan.validate`), the executor is unknown/unavailable, `out_dir` cannot be
    written, or it holds a campaign with a different config.
    """
    out = Path(out_dir)
    validate(cfg)  # fail fast here rather than once per trial in workers
    runner = make_executor(executor, workers, cfg.plugins, trial_timeout_s=trial_timeout_s)
    store = ResultStore(out)
    store.ensure_manifest(cfg)
    specs = expand(cfg, video_dir=out / "videos")
    if any(s.video for s in specs):
        (out / "videos").mkdir(parents=True, exist_ok=True)

    wanted = {s.key for s in specs}
    records = {r.key: r for r in store.read() if r.key in wanted}
    todo = [s for s in specs if s.key not in records]

    console = console or Console(stderr=True, soft_wrap=True)
    notes, todo = prepare(todo)  # an endpoint that cannot serve the methods stops the campaign here; the trials
    for note in notes:  # then carry what it learnt (reasoner.options.learnt) to the workers
        console.print(escape(f"preflight: {note}"))
    ok = sum(r.success for r in records.values())
    err = sum(r.error is not None for r in records.values())
    if progress and records:
        console.print(escape(f"resuming {out}: {len(records)} of {len(specs)} trials already recorded"))
    # A bar needs a terminal; in a log file (CI, nohup) it would print nothing until the end.
    lines = progress and not console.is_terminal

    started, resumed = time.monotonic(), len(records)
    beat = _Heartbeat(console, len(specs), started, HEARTBEAT_S) if lines and todo else None
    with store.appender() as appender, _progress(console, progress and not lines) as bar, beat or _nothing():
        task_id = bar.add_task(escape(cfg.task), total=len(specs), completed=len(records), ok=ok, err=err)
        for spec, record in runner.run(todo) if todo else ():
            record = _checked(spec, record)
            appender.append(record)
            records[record.key] = record
            ok += record.success
            err += record.error is not None
            bar.update(task_id, advance=1, ok=ok, err=err)
            if lines:
                elapsed = time.monotonic() - started
                eta = elapsed / (len(records) - resumed) * (len(specs) - len(records))
                console.print(escape(progress_line(record, len(records), len(specs), ok, err, elapsed, eta)),
                              highlight=False)
                if beat is not None:
                    beat.done(len(records))
    return [records[s.key] for s in specs if s.key in records]


HEARTBEAT_S = 10.0
"""In a log, a line at least this often while trials run, so a long trial is not mistaken for a hang."""


@contextlib.contextmanager
def _nothing() -> Iterator[None]:
    yield


class _Heartbeat:
    """A daemon thread that prints 'still running' when no trial has finished for `every_s` seconds."""

    def __init__(self, console: Console, total: int, started: float, every_s: float) -> None:
        self.console, self.total, self.started, self.every_s = console, total, started, every_s
        self.count, self.last = 0, started
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._beat, daemon=True, name="campaign-heartbeat")

    def __enter__(self) -> "_Heartbeat":
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join(timeout=1.0)

    def done(self, count: int) -> None:
        self.count, self.last = count, time.monotonic()

    def _beat(self) -> None:
        while not self.stop.wait(self.every_s / 4):
            now = time.monotonic()
            if now - self.last >= self.every_s:
                self.last = now
                self.console.print(escape(f"{self.count}/{self.total} still running: "
                                          f"[{_clock(now - self.started)} elapsed]"), highlight=False)


def progress_line(record: TrialRecord, done: int, total: int, ok: int, err: int,
                  elapsed_s: float | None = None, eta_s: float | None = None) -> str:
    """One plain line per finished trial, for logs: done/total, key, outcome, wall time, running counts,
    and the campaign's elapsed time and estimated time left (from this run's pace)."""
    outcome = "success" if record.success else "failure"
    line = f"{done}/{total} {record.key}: {outcome}, {record.wall_time:.2f} s wall ({ok} ok, {err} errors)"
    if elapsed_s is not None:
        line += f" [{_clock(elapsed_s)} elapsed" + (f", ~{_clock(eta_s)} left]" if eta_s is not None else "]")
    return line + (f"; error: {first_line(record.error)}" if record.error else "")


def _clock(seconds: float) -> str:
    m, s = divmod(int(round(seconds)), 60)
    return f"{m // 60}:{m % 60:02d}:{s:02d}" if m >= 60 else f"{m}:{s:02d}"


def first_line(text: str) -> str:
    return next((ln.strip() for ln in text.splitlines() if ln.strip()), "")


def error_summary(records: list[TrialRecord]) -> str | None:
    """'N of M trials errored; first: key: message', or None when no trial errored."""
    errored = [r for r in records if r.error]
    if not errored:
        return None
    first = errored[0]
    return (f"{len(errored)} of {len(records)} trials errored (they count as failures); "
            f"first: {first.key}: {first_line(first.error or '')}")


def _checked(spec: TrialSpec, record: TrialRecord) -> TrialRecord:
    """A record must carry its trial's identity, or resume would rerun that trial forever."""
    wrong = [f for f, v in spec.identity().items() if getattr(record, f) != v]
    if not wrong:
        return record
    return failed_record(
        spec,
        f"the executor returned a record whose {', '.join(wrong)} do not match the trial "
        f"(got key {record.key!r}); an executor must yield each spec with the record run_trial made for it",
    )
