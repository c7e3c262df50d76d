"""Export time per trial: a small tabletop campaign run inline, then exported as HDF5 and LeRobot at each
frame rate; per trial, the plain trial's wall time, the export's (re-run + recording + writing), the
overhead of recording and writing, frames and bytes written per trial.

    .venv/bin/python bench/bench_export.py [--task pour-single] [--method agentchord] [--condition drop]
        [--trials 2] [--seed 3] [--fps 10,5] [--set disturbance.drop_p=0.1 ...]

Rendering both 320x240 views dominates the recording (one pair per frame); the trial itself is re-run in
full, so export time is at least the trial's.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("MUJOCO_GL", "egl")

from kintsugi.campaign.plan import CampaignConfig  # noqa: E402
from kintsugi.campaign.runner import run_campaign  # noqa: E402
from kintsugi.core.config import parse_override  # noqa: E402
from kintsugi.export import export_campaign  # noqa: E402


def _size(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", default="pour-single")
    ap.add_argument("--method", default="agentchord")
    ap.add_argument("--condition", default="drop")
    ap.add_argument("--trials", type=int, default=2)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--fps", default="10,5")
    ap.add_argument("--set", action="append", default=None, dest="sets")
    args = ap.parse_args()
    sets = args.sets if args.sets is not None else ["disturbance.drop_p=0.1"]
    overrides = dict((".".join(k), v) for k, v in (parse_override(s) for s in sets))
    root = Path(tempfile.mkdtemp(prefix="bench_export_"))
    try:
        cfg = CampaignConfig(task=args.task, methods=[args.method], variants=["default"],
                             conditions=[args.condition], trials=args.trials, base_seed=args.seed, overrides=overrides)
        records = run_campaign(cfg, root / "campaign", workers=1, executor="inline", progress=False)
        plain = sum(r.wall_time for r in records) / len(records)
        from kintsugi.core.registry import TASKS

        sim = TASKS.get(args.task).factory().config(overrides).sim
        per_tick = max(1, round(sim.control_dt_s / sim.timestep_s))
        steps = sum(r.physics_steps for r in records) / len(records) / per_tick
        recovered = sum(bool(r.transitions) for r in records)
        print(f"campaign: {args.task} / {args.method} / {args.condition}, {len(records)} trials (seeds "
              f"{args.seed}-{args.seed + args.trials - 1}), {recovered} with a recovery, mean {steps:.0f} control "
              f"steps; plain trial {plain:.2f} s wall")
        print(f"{'format':8} {'fps':>4} {'frames/trial':>12} {'export s/trial':>15} {'overhead s/trial':>17} "
              f"{'MB/trial':>9}")
        for fps in (float(x) for x in args.fps.split(",")):
            for fmt in ("hdf5", "lerobot"):
                out = root / f"{fmt}-{fps:g}"
                t0 = time.perf_counter()
                rep = export_campaign(root / "campaign", fmt, out, fps=fps)
                per = (time.perf_counter() - t0) / len(rep.exported)
                frames = sum(e.frames for e in rep.exported) / len(rep.exported)
                print(f"{fmt:8} {fps:4g} {frames:12.0f} {per:15.2f} {per - plain:17.2f} "
                      f"{_size(out) / len(rep.exported) / 1e6:9.2f}"
                      + (f"  ({len(rep.refused)} refused)" if rep.refused else ""))
                shutil.rmtree(out)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    load = os.getloadavg() if hasattr(os, "getloadavg") else ("?",)
    print(f"machine: {platform.platform()} | {platform.processor() or platform.machine()} | "
          f"{os.cpu_count()} cores | load {load[0]:.1f} | MUJOCO_GL={os.environ.get('MUJOCO_GL')}")


if __name__ == "__main__":
    main()
