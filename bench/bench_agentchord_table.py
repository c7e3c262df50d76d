"""Table I of system-B campaigns (one results.jsonl each), as `kintsugi bench` prints it: the package's tables
(`kintsugi.campaign.tables.tables_for`, system B's Table I from `kintsugi/campaign/systems/tabletop.py`: success
with a Wilson 95 % interval, episode steps, sim, execution and modelled time, reasoning calls, the steps and
modelled time of completed trials, recoveries, recovery latency, and the paired figures against AgentChord on
the same seeds), then the detection delay read from the trials' event logs: a drop -> the monitor's firing,
the replan, or for a drop during a recovery the recovery watch's "recovery disturbed", in 10 ms control steps
(monitors that read the pads run every control step, so for them it is about the persistence window; checks
made by a verifier at sub-goals see the drop only when the action ends).

    .venv/bin/python bench/bench_agentchord_table.py runs/<campaign> [more campaigns...]
    .venv/bin/python bench/bench_agentchord_table.py --run [--tasks pour-single,...] [--suites table1,...]
        [--workers 2] [--trials N]   # run (or resume) the suites per task into runs/table1/<task>-<suite>

`--run` is Table I in one command: for every task and suite (`table1` = p 0.10, `table1-p05` = p 0.05,
every method, 20 trials) it runs `kintsugi bench <task> --suite <suite>` (resumable: finished trials are
kept), then prints the tables of all of them.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from rich.console import Console  # noqa: E402

from bench_mppi import machine  # noqa: E402
from kintsugi.campaign.render import print_tables  # noqa: E402
from kintsugi.campaign.stats import fmt, mean  # noqa: E402
from kintsugi.campaign.store import ResultStore, iter_records  # noqa: E402
from kintsugi.campaign.tables import TextTable, group_by_cell, tables_for  # noqa: E402
from kintsugi.core.errors import KintsugiError  # noqa: E402


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


def delay_table(records: list) -> TextTable:
    """Detection delay per cell, from the event logs (a diagnostic beside Table I, not a method figure)."""
    table = TextTable(title="Detection delay (drop -> detection), control steps, from the event logs",
                      columns=["Method", "Variant", "Condition", "n", "Mean", "Drops detected"])
    for (method, variant, condition), rs in group_by_cell(records).items():
        delays = [d for r in rs for d in detection_delays(r)]
        table.rows.append([method, variant, condition, str(len(rs)), fmt(mean(delays), 0), str(len(delays))])
    return table


def main() -> None:
    try:
        from bench.pages import Block, command_line, pop_page, table_lines, write_block
    except ModuleNotFoundError:  # run as a script: bench/ is on the path
        from pages import Block, command_line, pop_page, table_lines, write_block
    page, argv = pop_page(sys.argv[1:])  # --page docs/benchmarks-agentchord.md: write the tables there too
    lines: list[str] = []
    outs = run_suites(argv[1:]) if argv[:1] == ["--run"] else argv
    console = Console()
    print(f"machine: {machine()}")
    for out in outs:
        store = ResultStore(Path(out))
        records = list(iter_records(out))
        try:
            cfg = store.load_config()
        except KintsugiError:
            cfg = None
        task = cfg.task if cfg else (records[0].task if records else "tabletop")
        console.print(f"## {out}")
        print_tables([*tables_for(task, records, cfg), delay_table(records)], console)
        lines += [f"#### {out}", "", *table_lines([*tables_for(task, records, cfg), delay_table(records)])]
    if page:
        print(f"page: {write_block(page, Block('bench_agentchord_table', command_line(), lines))}")


if __name__ == "__main__":
    main()
