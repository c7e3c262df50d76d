"""Re-run one recorded trial with a recorder attached, and refuse it unless it is the trial on record.

Campaign records hold outcomes, not trajectories; trials are deterministic per seed, so the trajectory is
recovered by running the trial's spec again. What was recorded must come out again (scored success,
framework verdict, error or none, physics steps, episode steps, the atomic actions with their reach and
final tool positions, the recovery transitions): a difference is a `ReplayMismatch` naming the fields.
"""

from __future__ import annotations

import json
import time
from typing import Any

from kintsugi.core.errors import ConfigError, KintsugiError
from kintsugi.export.recorder import Episode, TrajectoryRecorder
from kintsugi.core.record import TrialRecord, TrialSpec


class ReplayMismatch(KintsugiError):
    """The re-run did not reproduce the stored record: exporting it would label someone else's trajectory."""


def frame_stride(control_hz: float, fps: float) -> int:
    """Control steps per exported frame; the frame rate must divide the control rate."""
    if fps <= 0:
        raise ConfigError(f"--fps must be positive, not {fps}")
    every = round(control_hz / fps)
    if every < 1 or abs(every * fps - control_hz) > 1e-6 * control_hz:
        rates = [control_hz / k for k in range(1, 21) if float(control_hz / k).is_integer()]
        raise ConfigError(f"--fps {fps:g} does not divide the control rate {control_hz:g} Hz; "
                          f"use one of {', '.join(f'{r:g}' for r in rates)}")
    return every


def episode_steps(record: TrialRecord) -> int | None:
    """The method's own episode-step count (the agentchord `metrics` event), if it reports one."""
    for e in record.events:
        if e.kind == "metrics":
            try:
                return int(json.loads(e.detail)["episode_steps"])
            except (ValueError, KeyError, TypeError):
                return None
    return None


def _fingerprint(r: TrialRecord) -> dict[str, Any]:
    return {
        "success": r.success, "framework_success": r.framework_success,
        "error": None if r.error is None else r.error.splitlines()[0],
        "physics_steps": r.physics_steps, "episode_steps": episode_steps(r),
        "actions": [(s.skill, s.reached, s.recovery, s.terminal) for s in r.skills],
        "transitions": [tuple(t) for t in r.transitions],
    }


def compare(stored: TrialRecord, again: TrialRecord) -> list[str]:
    """Fields where the re-run differs from the stored record ('' when it matches)."""
    a, b = _fingerprint(stored), _fingerprint(again)
    out = []
    for k in a:
        if a[k] != b[k]:
            if k == "actions":
                out.append(f"actions ({len(a[k])} recorded, {len(b[k])} re-run; first difference at "
                           f"{next((i for i, (x, y) in enumerate(zip(a[k], b[k])) if x != y), min(len(a[k]), len(b[k])))})")
            else:
                out.append(f"{k} (recorded {a[k]!r}, re-run {b[k]!r})")
    return out


def control_rate(task: Any, cfg: Any) -> float:
    """Control periods per second of the task's robot (what an exported frame rate must divide)."""
    if task.system == "tabletop":
        return 1.0 / cfg.sim.control_dt_s
    if task.system == "peg":
        n = max(1, round(1.0 / cfg.control.rate_hz / cfg.sim.timestep_s))
        return 1.0 / (n * cfg.sim.timestep_s)
    if task.system == "contact":
        n = max(1, round(1.0 / (INNER_HZ * cfg.sim.timestep_s)))
        return 1.0 / (n * cfg.sim.timestep_s)
    raise ConfigError(f"export knows the peg, tabletop and contact systems, not {task.system!r}")


INNER_HZ = 100.0
"""The contact robot's inner control rate (`ContactRobot`'s default, the rate its servos are commanded at)."""


def replay(spec: TrialSpec, stored: TrialRecord, fps: float, generic: bool = False) -> Episode:
    """Run `spec` again with a recorder attached; the episode, or ReplayMismatch / KintsugiError.

    `generic`: record through the step-level driver (`frames.FrameRecorder`, any system), else with the
    tabletop `TrajectoryRecorder` (graph-edge labels, the v2.1 and HDF5 tabletop layout)."""
    from kintsugi.core.registry import TASKS
    from kintsugi.core.resolve import split_overrides
    from kintsugi.core.runner import run_trial
    from kintsugi.export.frames import FrameRecorder

    task = TASKS.get(spec.task).factory()
    cfg = task.config(split_overrides(spec.overrides)[0])
    control_hz = control_rate(task, cfg)
    every = frame_stride(control_hz, fps)
    recorder = FrameRecorder(every) if generic else TrajectoryRecorder(every)
    start = time.perf_counter()
    try:
        again = run_trial(spec.model_copy(update={"video": None}), echo=recorder.echo, attach=recorder.attach)
        if again.error:
            raise KintsugiError(f"re-running {spec.key} failed: {again.error.splitlines()[0]}")
    except KintsugiError:
        raise
    except Exception as exc:  # noqa: BLE001 - one trial's crash is that trial's error, the export goes on
        raise KintsugiError(f"re-running {spec.key} raised {type(exc).__name__}: {exc}") from exc
    diffs = compare(stored, again)
    if diffs:
        raise ReplayMismatch(f"re-running {spec.key} did not reproduce its record: {'; '.join(diffs)}")
    if recorder.steps < recorder.every:
        raise KintsugiError(f"{spec.key}: the trial ran {recorder.steps} control steps, less than one frame "
                            f"at {fps:g} fps; nothing to export")
    if not generic:
        per_tick = max(1, round(cfg.sim.control_dt_s / cfg.sim.timestep_s))
        if recorder.steps != again.physics_steps // per_tick:
            raise KintsugiError(f"{spec.key}: the recorder saw {recorder.steps} control steps of the "
                                f"{again.physics_steps // per_tick} the trial ran")
    spec_of = getattr(task, "spec", None)
    instruction = getattr(spec_of, "instruction", None) or task.description
    ep = recorder.episode(spec.key, spec.task, instruction, again, control_hz)
    ep.meta |= {"spec": spec.model_dump(mode="json"), "config": cfg.model_dump(mode="json"),
                "control_hz": control_hz, "episode_steps": episode_steps(again),
                "recovered": bool(ep.recovery.any()), "replay_s": round(time.perf_counter() - start, 3),
                "transitions": [list(t) for t in again.transitions]}
    return ep
