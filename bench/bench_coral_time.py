"""Where a coral trial's time goes: wall and CPU seconds per simulated second, task by task, on this machine.

Runs one coral trial per task in this process (embedded reasoner, condition `all`) and prints, per task, the sim
time, the wall time, the process's CPU time (every thread: MPPI's rollout pool too) and both per simulated second,
the record's `time_breakdown_wall_s` (planning, physics, sysid, reasoning, other), the system identification's
wall seconds per cycle, the ground truth and the method's verdict. The load average before and after is printed
with each task: on a machine that other jobs share, wall time grows with the load and CPU time barely does, so
CPU per simulated second is the load-independent figure (a quiet 2-core machine's wall time is at most the CPU
time: the planner's two rollout threads share it).

Last line: one JSON object, per task {sim_s, wall_s, cpu_s, wall_per_sim, cpu_per_sim, sysid_s_per_cycle, success,
verdict, load}, and the machine.
Usage: .venv/bin/python bench/bench_coral_time.py [--tasks push-force,flip-box] [--seed 30000] [--set key=value ...]
       [--page docs/benchmarks-coral.md]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
# Nothing heavy is imported at the top: the sandbox's probe children import the parent's `__main__` script again
# (multiprocessing's rule for scripts), and a heavy one would count seconds per probe as reasoning time.

TASKS = ("push-pick-board", "pick-box", "pick-clutter", "push-force", "flip-box", "flip-wall")


def one(task: str, seed: int, overrides: dict, method: str) -> dict:
    from kintsugi.core.record import TrialSpec
    from kintsugi.core.runner import run_trial

    load0 = os.getloadavg()[0]
    wall0, cpu0 = time.perf_counter(), time.process_time()
    rec = run_trial(TrialSpec(task=task, method=method, variant="default", condition="all", seed=seed,
                              overrides=overrides))
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    fig = rec.method_figures or {}
    spent = fig.get("time_breakdown_wall_s") or {}
    cycles = sum(1 for e in rec.events if e.kind == "sysid")
    sim = max(rec.sim_time, 1e-9)
    return {"task": task, "seed": seed, "sim_s": round(rec.sim_time, 2), "wall_s": round(wall, 1),
            "cpu_s": round(cpu, 1), "wall_per_sim": round(wall / sim, 2), "cpu_per_sim": round(cpu / sim, 2),
            "breakdown_wall_s": spent, "sysid_cycles": cycles,
            "sysid_s_per_cycle": round(spent.get("sysid", 0.0) / cycles, 2) if cycles else None,
            "attempts": len(fig.get("attempts") or []), "success": rec.success, "verdict": rec.framework_success,
            "error": (rec.error or "")[:200] or None, "load": [round(load0, 1), round(os.getloadavg()[0], 1)]}


def main() -> None:
    from bench_mppi import machine

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default=",".join(TASKS))
    ap.add_argument("--seed", type=int, default=30000)
    ap.add_argument("--method", default="coral")
    ap.add_argument("--set", action="append", default=[], help="config override key=value (JSON values)")
    ap.add_argument("--page", help="also write the table into this benchmark page (docs/benchmarks-coral.md)")
    args = ap.parse_args()
    overrides = {}
    for item in args.set:
        key, _, value = item.partition("=")
        try:
            overrides[key] = json.loads(value)
        except json.JSONDecodeError:
            overrides[key] = value
    print(f"machine: {machine()}")
    rows = []
    for task in args.tasks.split(","):
        r = one(task, args.seed, overrides, args.method)
        rows.append(r)
        print(f"{task} seed {r['seed']}: sim {r['sim_s']} s, wall {r['wall_s']} s ({r['wall_per_sim']}x), "
              f"CPU {r['cpu_s']} s ({r['cpu_per_sim']}x), {r['attempts']} attempts, sysid "
              f"{r['sysid_s_per_cycle']} s/cycle over {r['sysid_cycles']}, breakdown {r['breakdown_wall_s']}, "
              f"truth {'success' if r['success'] else 'failure'}, verdict {'success' if r['verdict'] else 'failure'}, "
              f"load {r['load'][0]} -> {r['load'][1]}" + (f", error {r['error']}" if r["error"] else ""), flush=True)
    if args.page:
        try:
            from bench.pages import Block, command_line, write_block
        except ModuleNotFoundError:  # run as a script: bench/ is on the path
            from pages import Block, command_line, write_block
        lines = ["| task (seed) | sim s | wall s | wall / sim | CPU s | CPU / sim | attempts | sysid s / cycle | "
                 "planning / physics / sysid / reasoning wall s | truth / verdict | load |",
                 "|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            b = r["breakdown_wall_s"]
            lines.append(f"| {r['task']} ({r['seed']}) | {r['sim_s']} | {r['wall_s']} | {r['wall_per_sim']} | {r['cpu_s']} "
                         f"| {r['cpu_per_sim']} | {r['attempts']} | {r['sysid_s_per_cycle']} | "
                         f"{b.get('planning')} / {b.get('physics')} / {b.get('sysid')} / {b.get('reasoning')} | "
                         f"{'S' if r['success'] else 'F'} / {'S' if r['verdict'] else 'F'} | "
                         f"{r['load'][0]}-{r['load'][1]} |")
        print(f"page: {write_block(args.page, Block('bench_coral_time', command_line(), lines))}")
    print(json.dumps({"machine": machine(), "trials": rows}))


if __name__ == "__main__":
    main()
