"""AgentChord under every disturbance: per task and condition, success with a Wilson 95 % interval, false
successes (the method's verdict success, the ground truth failure: F+G-), trial errors, mean episode steps and
run-time reasoning calls; then, for campaigns that also ran baselines, the paired episode steps under each
condition on the seeds both AgentChord and the baseline solved.

    .venv/bin/python bench/bench_agentchord_disturbances.py runs/<campaign> [more campaigns...]
    .venv/bin/python bench/bench_agentchord_disturbances.py --run [--tasks a,b] [--conditions drop,shift,knock,all]
        [--trials N] [--base-seed S] [--workers W] [--out runs/disturbances]

A campaign given later replaces an earlier one's record of the same trial (task/method/variant/condition/seed):
chosen seeds re-run on a newer commit. `--run` runs (or resumes) `kintsugi bench <task> --methods agentchord --conditions <those the task has>` per task
into <out>/<task>, then prints the tables; `--page PAGE [--name BLOCK]` also writes them into a benchmark page. `--base-seed` defaults to 40000; that block has been looked at while
developing, so figures meant for unseen seeds take a block no run has used (the benchmark page names them).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kintsugi.campaign.stats import wilson_interval  # noqa: E402
from kintsugi.campaign.store import iter_records  # noqa: E402

TASKS = ("pour-single", "pour-dual", "rearrange-table", "handover-block", "coffee-tray", "stack-blocks",
         "flank-box", "block-in-bin")
CONDITIONS = ("drop", "shift", "knock", "all")


def steps_of(r) -> int | None:  # noqa: ANN001 - a TrialRecord
    figures = r.method_figures or {}
    return figures.get("episode_steps") if isinstance(figures, dict) else None


def calls_of(r) -> int:  # noqa: ANN001
    figures = r.method_figures or {}
    return int(figures.get("runtime_reasoning_calls", 0)) if isinstance(figures, dict) else 0


def cells(records) -> dict:  # noqa: ANN001
    out: dict = defaultdict(list)
    for r in records:
        out[(r.task, r.method, r.condition)].append(r)
    return out


def disturbance_rows(by_cell: dict, method: str = "agentchord") -> list[str]:
    rows = ["| task | condition | n | success % [95 % CI] | F+G- | trial errors | mean steps | run-time calls |",
            "|---|---|---|---|---|---|---|---|"]
    order = {c: i for i, c in enumerate(CONDITIONS)}
    for (task, m, cond), rs in sorted(by_cell.items(), key=lambda kv: (kv[0][0], order.get(kv[0][2], 9))):
        if m != method:
            continue
        n, k = len(rs), sum(r.success for r in rs)
        lo, hi = wilson_interval(k, n)
        fpos = sum(bool(r.framework_success) and not r.success for r in rs)
        errors = sum(r.error is not None for r in rs)
        steps = [s for s in map(steps_of, rs) if s is not None]
        mean_steps = f"{sum(steps) / len(steps):.0f}" if steps else "-"
        calls = sum(map(calls_of, rs))
        rows.append(f"| {task} | {cond} | {n} | {100 * k / n:.0f} [{100 * lo:.0f}-{100 * hi:.0f}] ({k}/{n}) | "
                    f"{fpos} | {errors} | {mean_steps} | {calls} |")
    return rows


def paired_rows(by_cell: dict, method: str = "agentchord") -> list[str]:
    rows = ["| task | condition | baseline | seeds both solved | baseline steps | agentchord steps | fewer? |",
            "|---|---|---|---|---|---|---|"]
    for (task, m, cond), rs in sorted(by_cell.items()):
        if m == method or (task, method, cond) not in by_cell:
            continue
        ours = {r.seed: r for r in by_cell[(task, method, cond)] if r.success}
        both = [(r, ours[r.seed]) for r in rs if r.success and r.seed in ours]
        pairs = [(steps_of(b), steps_of(a)) for b, a in both if steps_of(b) is not None and steps_of(a) is not None]
        if not pairs:
            continue
        b = sum(p[0] for p in pairs) / len(pairs)
        a = sum(p[1] for p in pairs) / len(pairs)
        rows.append(f"| {task} | {cond} | {m} | {len(pairs)} | {b:.1f} | {a:.1f} | {'yes' if a < b else 'no'} |")
    return rows if len(rows) > 2 else []


def run(tasks: list[str], conditions: list[str], trials: int, base_seed: int, workers: int, out: Path) -> list[Path]:
    dirs = []
    for task in tasks:
        conds = [c for c in conditions if c != "knock" or _has_knock(task)]
        d = out / task
        subprocess.run([str(Path(sys.executable).with_name("kintsugi")), "bench", task, "--methods", "agentchord",
                        "--conditions", ",".join(conds), "--trials", str(trials), "--workers", str(workers),
                        "--base-seed", str(base_seed), "--out", str(d)], check=False)
        dirs.append(d)
    return dirs


def _has_knock(task: str) -> bool:
    from kintsugi.worlds.tabletop.tasks import SPECS

    return any(s.name == task and s.knock is not None for s in SPECS)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("campaigns", nargs="*", type=Path)
    ap.add_argument("--run", action="store_true")
    ap.add_argument("--tasks", default=",".join(TASKS))
    ap.add_argument("--conditions", default=",".join(CONDITIONS))
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--base-seed", type=int, default=40000)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--out", type=Path, default=Path("runs/disturbances"))
    ap.add_argument("--page", help="also write the tables into this benchmark page (with --name)")
    ap.add_argument("--name", default="bench_agentchord_disturbances", help="the page's block name")
    a = ap.parse_args()
    dirs = list(a.campaigns)
    if a.run:
        dirs += run(a.tasks.split(","), a.conditions.split(","), a.trials, a.base_seed, a.workers, a.out)
    if not dirs:
        ap.error("give campaign directories, or --run")
    latest = {r.key: r for d in dirs for r in iter_records(d)}  # a later campaign's record of a trial wins
    records = list(latest.values())
    by_cell = cells(records)
    print("\n".join(disturbance_rows(by_cell)))
    paired = paired_rows(by_cell)
    if paired:
        print("\nPaired episode steps (seeds both solved):\n" + "\n".join(paired))
    if a.page:
        from bench.pages import Block, command_line, write_block

        lines = [*disturbance_rows(by_cell), *(["", "Paired episode steps (seeds both solved):", "", *paired] if paired else [])]
        print(f"page: {write_block(a.page, Block(a.name, command_line(), lines))}")


if __name__ == "__main__":
    main()
