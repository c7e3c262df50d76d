"""Behaviour cloning beside the method it learned from, under the same condition and seeds (System A):
per condition, a recovery campaign on training seeds, exported as robomimic HDF5 at the control rate, a linear
policy fitted with numpy (base pose, wrist force and time features), then both run on the same held-out seeds.

    .venv/bin/python bench/bench_policy.py [--conditions friction,pose] [--train 8] [--eval 10] [--bases 40]

Prints each one's ground-truth success with its Wilson 95 % interval (n = --eval) and writes the table into
docs/datasets.md (block `bench_policy`; `--no-page` only prints).
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

from bench.pages import Block, command_line, write_block  # noqa: E402
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


def compare(args: argparse.Namespace, condition: str, root: Path) -> list[tuple[str, int, int]]:
    """Train on `condition`'s training seeds, then (method, successes, n) for the method and its clone."""
    t0 = time.perf_counter()
    cfg = CampaignConfig(task=args.task, methods=[args.method], variants=[args.variant], conditions=[condition],
                         trials=args.train, base_seed=0)
    records = run_campaign(cfg, root / "train", workers=1, executor="inline", progress=False)
    export_campaign(root / "train", "hdf5", root / "data", trials="success", fps=args.fps)
    policy = fit_hdf5(root / "data" / "demo.hdf5", ("base_pose", "wrist_force"), bases=args.bases)
    path = policy.save(root / "bc.npz")
    print(f"{condition}: trained on {policy.meta['demos']} successful demos of {len(records)} {args.method} trials "
          f"({time.perf_counter() - t0:.0f} s)")
    out = []
    for method, over in ((args.method, {}), ("policy", {"method.path": str(path)})):
        ok = sum(bool(run_trial(TrialSpec(task=args.task, method=method, variant=args.variant, condition=condition,
                                          seed=s, overrides=over)).success)
                 for s in range(1000, 1000 + args.eval))
        lo, hi = wilson(ok, args.eval)
        print(f"{method:10s} {condition}: {ok}/{args.eval} = {ok / args.eval:.0%} (Wilson 95 % {lo:.0%}-{hi:.0%})")
        out.append((method, ok, args.eval))
    out.append(("demos", int(policy.meta["demos"]), len(records)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", default="peg-insertion")
    ap.add_argument("--method", default="recovery")
    ap.add_argument("--variant", default="round")
    ap.add_argument("--conditions", default="friction,pose")
    ap.add_argument("--train", type=int, default=8)
    ap.add_argument("--eval", type=int, default=10)
    ap.add_argument("--bases", type=int, default=40)
    ap.add_argument("--fps", type=float, default=250.0)
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/datasets.md")
    args = ap.parse_args()
    root = Path(tempfile.mkdtemp(prefix="bench_policy_"))
    lines = [f"| condition | {args.method} (the teacher) | policy (linear BC) | demos (successful / trained) |",
             "|---|---|---|---|"]
    for condition in args.conditions.split(","):
        rows = {m: (k, n) for m, k, n in compare(args, condition, root / condition)}
        cells = []
        for m in (args.method, "policy"):
            k, n = rows[m]
            lo, hi = wilson(k, n)
            cells.append(f"{k}/{n} (Wilson 95 % {lo:.0%}-{hi:.0%})")
        lines.append(f"| {condition} | {cells[0]} | {cells[1]} | {rows['demos'][0]} / {rows['demos'][1]} |")
    lines += ["", f"{args.task} ({args.variant}); training seeds 0-{args.train - 1}, the same held-out seeds "
              f"1000-{999 + args.eval} for both; ground-truth success."]
    if not args.no_page:
        write_block(Path(__file__).resolve().parents[1] / "docs" / "datasets.md", Block("bench_policy", command_line(), lines))


if __name__ == "__main__":
    main()
