"""Behaviour cloning beside the method it learned from, under the same condition and seeds (System A):
a recovery campaign on training seeds, exported as robomimic HDF5 at the control rate, a linear policy fitted
with numpy (base pose, wrist force and time features), then both run on held-out seeds.

    .venv/bin/python bench/bench_policy.py [--condition angle] [--train 8] [--eval 10] [--bases 40]

Prints each one's ground-truth success with its Wilson 95 % interval (n = --eval).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("MUJOCO_GL", "egl")

from kintsugi.campaign.plan import CampaignConfig  # noqa: E402
from kintsugi.campaign.runner import run_campaign  # noqa: E402
from kintsugi.core.record import TrialSpec  # noqa: E402
from kintsugi.core.runner import run_trial  # noqa: E402
from kintsugi.export import export_campaign  # noqa: E402
from kintsugi.methods.policy.train import fit_hdf5  # noqa: E402


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    if n == 0:
        return 0.0, 1.0
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, c - h), min(1.0, c + h)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", default="peg-insertion")
    ap.add_argument("--method", default="recovery")
    ap.add_argument("--variant", default="round")
    ap.add_argument("--condition", default="angle")
    ap.add_argument("--train", type=int, default=8)
    ap.add_argument("--eval", type=int, default=10)
    ap.add_argument("--bases", type=int, default=40)
    ap.add_argument("--fps", type=float, default=250.0)
    args = ap.parse_args()
    root = Path(tempfile.mkdtemp(prefix="bench_policy_"))
    t0 = time.perf_counter()
    cfg = CampaignConfig(task=args.task, methods=[args.method], variants=[args.variant], conditions=[args.condition],
                         trials=args.train, base_seed=0)
    records = run_campaign(cfg, root / "train", workers=1, executor="inline", progress=False)
    export_campaign(root / "train", "hdf5", root / "data", trials="success", fps=args.fps)
    policy = fit_hdf5(root / "data" / "demo.hdf5", ("base_pose", "wrist_force"), bases=args.bases)
    path = policy.save(root / "bc.npz")
    print(f"trained on {policy.meta['demos']} successful demos of {len(records)} {args.method} trials "
          f"({time.perf_counter() - t0:.0f} s)")
    seeds = range(1000, 1000 + args.eval)
    for method, over in ((args.method, {}), ("policy", {"method.path": str(path)})):
        ok = 0
        for s in seeds:
            r = run_trial(TrialSpec(task=args.task, method=method, variant=args.variant, condition=args.condition,
                                    seed=s, overrides=over))
            ok += bool(r.success)
        lo, hi = wilson(ok, args.eval)
        print(f"{method:10s} {args.condition}: {ok}/{args.eval} = {ok / args.eval:.0%} (Wilson 95 % {lo:.0%}-{hi:.0%})")


if __name__ == "__main__":
    main()
