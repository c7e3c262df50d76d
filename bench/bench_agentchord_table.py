"""Table I figures of a system-B campaign (one results.jsonl): per method, ground-truth success with a Wilson
95 % interval, mean episode steps, sim time, execution time (sim + measured reasoning), modelled execution
time (sim + calls x 5 s), the steps and modelled time of the trials it completed (the paper's "steps executed
to complete a task"), reasoning calls after planning, recoveries, recovery latency (firing -> first
recovery command), and detection delay (a drop -> the monitor's firing, the replan, or for a drop during a recovery
the recovery watch's "recovery disturbed", in 10 ms control steps:
monitors that read the pads run every control step, so for them it is about the persistence window; checks
made by a verifier at sub-goals see the drop only when the action ends).

    .venv/bin/python bench/bench_agentchord_table.py runs/<campaign> [more campaigns...]
    .venv/bin/python bench/bench_agentchord_table.py --run [--tasks pour-single,...] [--suites table1,...]
        [--workers 2] [--trials N]   # run (or resume) the suites per task into runs/table1/<task>-<suite>

`--run` is Table I in one command: for every task and suite (`table1` = p 0.10, `table1-p05` = p 0.05,
every method, 20 trials) it runs `kintsugi bench <task> --suite <suite>` (resumable: finished trials are
kept), then prints the table of all of them. Latency steps = the largest recovery latency seen.
"""

from __future__ import annotations

import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kintsugi.campaign.stats import format_rate, mean  # noqa: E402
from kintsugi.campaign.store import iter_records  # noqa: E402
from kintsugi.methods.agentchord.method import metrics_of  # noqa: E402


CONTROL_DT_S = 0.01


def detection_delays(r) -> list[float]:  # noqa: ANN001 - a TrialRecord
    drops = [e.t for e in r.events if e.kind == "disturbance"]
    found = [e.t for e in r.events if e.kind in ("monitor", "replan", "backtrack", "recovery disturbed")]
    out = []
    for t in drops:
        after = [f for f in found if f >= t]
        if after:
            out.append((min(after) - t) / CONTROL_DT_S)
    return out


TABLE1_TASKS = ("pour-single", "pour-dual", "rearrange-table", "handover-block", "coffee-tray")


def run_suites(argv: list[str]) -> list[str]:
    import argparse
    import subprocess

    ap = argparse.ArgumentParser(prog="bench_agentchord_table.py --run")
    ap.add_argument("--tasks", default=",".join(TABLE1_TASKS))
    ap.add_argument("--suites", default="table1,table1-p05")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--trials", type=int, default=None)
    ap.add_argument("--root", default="runs/table1")
    args = ap.parse_args(argv)
    kintsugi = str(Path(sys.executable).with_name("kintsugi"))
    outs = []
    for task in args.tasks.split(","):
        for suite in args.suites.split(","):
            out = f"{args.root}/{task}-{suite}"
            cmd = [kintsugi, "bench", task, "--suite", suite, "--workers", str(args.workers), "--out", out]
            if args.trials:
                cmd += ["--trials", str(args.trials)]
            print("$", " ".join(cmd[1:]), flush=True)
            subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL)
            outs.append(out)
    return outs


def paired(rs: list, reference: list) -> str:
    """Mean steps and execution time over the seeds that both this method and the reference solved: the like-for-like
    cost, which a mean over all trials hides when one method finishes (at length) trials the other fails early."""
    ok = {r.seed: metrics_of(r) for r in reference if r.success and metrics_of(r) is not None}
    pairs = [(metrics_of(r), ok[r.seed]) for r in rs if r.success and r.seed in ok and metrics_of(r) is not None]
    if not pairs or rs[0].method == "agentchord":
        return "-"
    # A tenth of a step and a hundredth of a second: on the tasks where a drop leaves nothing to skip, the two
    # differ by less than the whole-step, tenth-second rounding of the other columns.
    return (f"{mean(a.episode_steps for a, _ in pairs):.1f} vs {mean(b.episode_steps for _, b in pairs):.1f} / "
            f"{mean(a.execution_time_s for a, _ in pairs):.2f} vs {mean(b.execution_time_s for _, b in pairs):.2f} / "
            f"{mean(a.modelled_execution_time_s for a, _ in pairs):.1f} vs "
            f"{mean(b.modelled_execution_time_s for _, b in pairs):.1f} ({len(pairs)})")


def completed(rs: list) -> str:
    """Mean steps and modelled execution time over the trials the method completed (succeeded)."""
    done = [m for r in rs if r.success and (m := metrics_of(r)) is not None]
    if not done:
        return "-"
    return f"{mean(m.episode_steps for m in done):.0f} / {mean(m.modelled_execution_time_s for m in done):.1f}"


def main() -> None:
    outs = run_suites(sys.argv[2:]) if sys.argv[1:2] == ["--run"] else sys.argv[1:]
    reference = defaultdict(list)  # agentchord's trials per (task, condition, p), from any of the campaigns given
    for out in outs:
        for r in iter_records(out):
            if r.method == "agentchord":
                reference[(r.task, r.condition, r.params.get("drop_p"))].append(r)
    for out in outs:
        groups = defaultdict(list)
        for r in iter_records(out):
            groups[(r.condition, r.params.get("drop_p"), r.method)].append(r)
        print(f"## {out}")
        print("| condition | p | method | n | success % [95% CI] | steps | sim s | exec s | modelled s | runtime calls "
              "| completed: steps / modelled s | recoveries | latency steps | detect delay steps (mean, n) | errors "
              "| steps / exec s / modelled s where it and agentchord both succeed: it vs agentchord (n) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for (cond, p, method), rs in sorted(groups.items(), key=lambda kv: (str(kv[0][0]), str(kv[0][1]), kv[0][2])):
            ms = [metrics_of(r) for r in rs]
            have = [m for m in ms if m is not None]
            steps = mean(m.episode_steps for m in have) if have else float("nan")
            lat = [x for m in have for x in m.recovery_latency_steps]
            delays = [d for r in rs for d in detection_delays(r)]
            delay = f"{mean(delays):.0f}, {len(delays)}" if delays else "-"
            print(f"| {cond} | {p} | {method} | {len(rs)} | {format_rate(sum(r.success for r in rs), len(rs))} | "
                  f"{steps:.0f} | {mean(r.sim_time for r in rs):.1f} | "
                  f"{mean(m.execution_time_s for m in have) if have else float('nan'):.1f} | "
                  f"{mean(m.modelled_execution_time_s for m in have) if have else float('nan'):.1f} | "
                  f"{mean(m.runtime_reasoning_calls for m in have) if have else float('nan'):.1f} | "
                  f"{completed(rs)} | {sum(m.recoveries for m in have)} | {max(lat) if lat else '-'} | {delay} | "
                  f"{sum(1 for r in rs if r.error)} | {paired(rs, reference[(rs[0].task, cond, p)])} |")


if __name__ == "__main__":
    main()
