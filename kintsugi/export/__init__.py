"""Trajectory export for policy learning (AgentChord IV-E): chosen trials of a campaign of any system (peg,
tabletop, contact), re-run with a recorder, written as a LeRobot v3.0 dataset (`lerobot`), a robomimic HDF5
file (`hdf5`) or, for tabletop campaigns, LeRobot's older v2.1 layout (`lerobot-v2.1`), with nominal/recovery
segment labels; or, as `trajectory`, each trial's command at every control period for the replay policy.

`export_campaign` is what `kintsugi export` calls. Each chosen trial is re-run from its recorded spec
(trials are deterministic per seed) and checked against its record (`replay.compare`); a trial that does
not reproduce is refused by name, never exported.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Literal

import kintsugi
from kintsugi.core.errors import ConfigError, KintsugiError
from kintsugi.export.select import parse_filter
from kintsugi.core.record import TrialSpec

Format = Literal["lerobot", "hdf5", "lerobot-v2.1", "trajectory"]
FORMATS = ("hdf5", "lerobot", "lerobot-v2.1", "trajectory")
MANIFEST = "export.json"


@dataclass
class Exported:
    key: str
    frames: int
    control_steps: int
    recovered: bool
    success: bool
    seconds: float
    """Wall time of the re-run with recording and writing."""


@dataclass
class ExportReport:
    out: Path
    path: Path | None
    exported: list[Exported] = field(default_factory=list)
    refused: list[tuple[str, str]] = field(default_factory=list)


def _check_out(out: Path) -> None:
    from kintsugi.core.outputs import check_output_dir

    check_output_dir(out, "export directory")
    if out.exists() and any(out.iterdir()):
        raise ConfigError(f"export directory {out} is not empty; choose a new --out (an export is never merged "
                          "into an older one)")


def export_campaign(campaign_dir: str | Path, fmt: Format, out: str | Path, trials: str | None = None,
                    fps: float = 10.0, on_trial: Callable[[str, str], None] | None = None) -> ExportReport:
    """Export the trials of `campaign_dir` that `trials` keeps; raise KintsugiError before any re-run on bad
    input (unknown format, bad filter, no match, v2.1 of a task that is not tabletop, a non-embedded reasoner).

    Tabletop trials in `hdf5` and `lerobot-v2.1` keep the tabletop recorder's layout (graph-edge labels,
    14 joint/gripper actions); every other export records through the step-level driver (`frames`)."""
    import time

    from kintsugi.campaign.bootstrap import bootstrap
    from kintsugi.campaign.store import ResultStore
    from kintsugi.export.replay import control_rate, frame_stride, replay
    from kintsugi.core.registry import TASKS

    if fmt not in FORMATS:
        raise ConfigError(f"unknown export format {fmt!r}; known: {', '.join(FORMATS)}")
    _dependencies(fmt)
    out = Path(out)
    store = ResultStore(campaign_dir)
    cfg = store.load_config()
    records = store.read()
    if not records:
        raise KintsugiError(f"{store.results_path} holds no trial record; run the campaign first")
    filt = parse_filter(trials)
    chosen = [r for r in records if filt.keeps(r)]
    if not chosen:
        raise KintsugiError(f"no trial of {campaign_dir} matches --trials {filt.text!r} ({len(records)} recorded, "
                            f"e.g. {records[0].key})")
    bootstrap(cfg.plugins, cfg.task)
    entry = TASKS.get(cfg.task)
    task = entry.factory()
    tabletop = task.system == "tabletop"
    if fmt == "lerobot-v2.1" and not tabletop:
        raise ConfigError(f"--format lerobot-v2.1 is the tabletop (system B) layout; task {cfg.task!r} is "
                          f"{task.system}: use --format lerobot (v3.0) or hdf5")
    if cfg.reasoner.backend != "embedded":
        raise ConfigError(f"export re-runs each trial, and the {cfg.reasoner.backend!r} reasoner's replies are not "
                          "replayed from the record; export supports campaigns on the embedded reasoner")
    from kintsugi.core.resolve import split_overrides

    frame_stride(control_rate(task, task.config(split_overrides(cfg.overrides)[0])), fps)
    generic = fmt == "lerobot" or not tabletop
    _check_out(out)
    source = {"campaign": str(Path(campaign_dir).resolve()), "task": cfg.task, "system": task.system,
              "filter": filt.text,
              "config": cfg.model_dump(mode="json")}
    report = ExportReport(out=out, path=None)
    if fmt == "trajectory":
        from kintsugi.export.trajectories import export_trajectories

        specs = [(TrialSpec(task=r.task, method=r.method, variant=r.variant, condition=r.condition, seed=r.seed,
                            overrides=cfg.overrides, reasoner=cfg.reasoner), r) for r in chosen]
        export_trajectories(specs, out, report, Exported, on_trial)
        if not report.exported:
            raise KintsugiError("no trial could be exported (" + "; ".join(f"{k}: {w}" for k, w in report.refused) + ")")
        report.path = out
        _manifest(out, fmt, fps, source, report)
        return report
    writer = None
    try:
        for r in chosen:
            spec = TrialSpec(task=r.task, method=r.method, variant=r.variant, condition=r.condition, seed=r.seed,
                             overrides=cfg.overrides, reasoner=cfg.reasoner)
            start = time.perf_counter()
            try:
                ep = replay(spec, r, fps, generic=generic)
            except KintsugiError as exc:
                report.refused.append((r.key, str(exc)))
                if on_trial is not None:
                    on_trial(r.key, f"refused: {exc}")
                continue
            if writer is None:
                out.mkdir(parents=True, exist_ok=True)
                writer = _writer(fmt, out, source)
            writer.add(ep)
            done = Exported(ep.key, ep.length, ep.control_steps, bool(ep.recovery.any()), ep.success,
                            round(time.perf_counter() - start, 3))
            report.exported.append(done)
            if on_trial is not None:
                on_trial(r.key, f"{done.frames} frames ({done.control_steps} control steps)"
                                f"{', recovery' if done.recovered else ''}, {done.seconds:.1f} s")
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    if writer is None:
        reasons = "; ".join(f"{k}: {why}" for k, why in report.refused)
        raise KintsugiError(f"no trial could be exported ({reasons})")
    report.path = writer.close()
    _manifest(out, fmt, fps, source, report)
    return report


def _manifest(out: Path, fmt: str, fps: float, source: dict, report: ExportReport) -> None:
    manifest = {"kintsugi_version": kintsugi.__version__, "format": fmt, "fps": fps, **source,
                "exported": [vars(e) for e in report.exported],
                "refused": [{"key": k, "reason": why} for k, why in report.refused]}
    (out / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")


def _dependencies(fmt: Format) -> None:
    """Fail before any re-run when the format's optional library is missing."""
    if fmt == "hdf5":
        from kintsugi.export.hdf5 import _h5py

        _h5py()
    elif fmt != "trajectory":
        from kintsugi.export.lerobot import _pyarrow

        _pyarrow()


def _writer(fmt: Format, out: Path, source: dict):  # noqa: ANN202 - either writer
    if fmt == "hdf5":
        from kintsugi.export.hdf5 import Hdf5Writer

        return Hdf5Writer(out, source)
    if fmt == "lerobot":
        from kintsugi.export.lerobot_v3 import LeRobotV3Writer

        return LeRobotV3Writer(out, source)
    from kintsugi.export.lerobot import LeRobotWriter

    return LeRobotWriter(out, source)


__all__ = ["ExportReport", "Exported", "export_campaign"]
