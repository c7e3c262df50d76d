"""`--format trajectory`: each chosen trial re-run with a `TickRecorder` and saved as `<key>.npz`, the command of
every control period (with a tabletop trial's atomic-action starts and a contact trial's restarts), for the
replay policy: `kintsugi run <task> --method policy --set method.path=<file>` runs it again step for step."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

from kintsugi.core.errors import KintsugiError
from kintsugi.core.record import TrialRecord, TrialSpec


def file_name(key: str) -> str:
    return key.replace("/", "__") + ".npz"


def export_trajectories(specs: list[tuple[TrialSpec, TrialRecord]], out: Path, report: Any, exported: type,
                        on_trial: Callable[[str, str], None] | None = None) -> None:
    """Re-run, check against the record (`replay.compare`), save; refusals go to `report.refused`."""
    from kintsugi.core.runner import run_trial
    from kintsugi.export.replay import compare
    from kintsugi.export.select import had_recovery
    from kintsugi.methods.policy.trajectory import TickRecorder

    for spec, stored in specs:
        start = time.perf_counter()
        rec = TickRecorder()
        try:
            again = run_trial(spec, attach=rec.attach)
            diffs = compare(stored, again)
            if again.error or diffs:
                why = again.error.splitlines()[0] if again.error else "; ".join(diffs)
                raise KintsugiError(f"re-running {spec.key} did not reproduce its record: {why}")
        except KintsugiError as exc:
            report.refused.append((spec.key, str(exc)))
            if on_trial is not None:
                on_trial(spec.key, f"refused: {exc}")
            continue
        traj = rec.trajectory(again)
        out.mkdir(parents=True, exist_ok=True)
        traj.save(out / file_name(spec.key))
        done = exported(spec.key, len(traj.actions), len(traj.actions), had_recovery(again), bool(again.success),
                        round(time.perf_counter() - start, 3))
        report.exported.append(done)
        if on_trial is not None:
            on_trial(spec.key, f"{done.control_steps} control steps -> {file_name(spec.key)}")
