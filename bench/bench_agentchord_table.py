"""Table I figures of a system-B campaign (one results.jsonl): per method, ground-truth success with a Wilson
95 % interval, mean episode steps, sim time, execution time (sim + measured reasoning), modelled execution
time (sim + calls x 5 s), reasoning calls after planning, recoveries, recovery latency (firing -> first
recovery command), and detection delay (a drop -> the monitor's firing or the replan, in 10 ms control steps;
monitors are read after each atomic action, so this is the rest of the action in which the drop happened).

    .venv/bin/python bench/bench_agentchord_table.py runs/<campaign> [more campaigns...]
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
    found = [e.t for e in r.events if e.kind in ("monitor", "replan", "backtrack")]
    out = []
    for t in drops:
        after = [f for f in found if f >= t]
        if after:
            out.append((min(after) - t) / CONTROL_DT_S)
    return out


def main() -> None:
    for out in sys.argv[1:]:
        groups = defaultdict(list)
        for r in iter_records(out):
            groups[(r.condition, r.params.get("drop_p"), r.method)].append(r)
        print(f"## {out}")
        print("| condition | p | method | n | success % [95% CI] | steps | sim s | exec s | modelled s | runtime calls "
              "| recoveries | latency steps | detect delay steps (mean, n) | errors |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
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
                  f"{sum(m.recoveries for m in have)} | {max(lat) if lat else '-'} | {delay} | "
                  f"{sum(1 for r in rs if r.error)} |")


if __name__ == "__main__":
    main()
