"""Table I figures of a system-B campaign (one results.jsonl): per method, ground-truth success with a Wilson
95 % interval, mean episode steps, sim time, execution time (sim + measured reasoning), modelled execution
time (sim + calls x 5 s), reasoning calls after planning, recoveries, and recovery latency.

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


def main() -> None:
    for out in sys.argv[1:]:
        groups = defaultdict(list)
        for r in iter_records(out):
            groups[(r.condition, r.params.get("drop_p"), r.method)].append(r)
        print(f"## {out}")
        print("| condition | p | method | n | success % [95% CI] | steps | sim s | exec s | modelled s | runtime calls "
              "| recoveries | latency steps | errors |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for (cond, p, method), rs in sorted(groups.items(), key=lambda kv: (str(kv[0][0]), str(kv[0][1]), kv[0][2])):
            ms = [metrics_of(r) for r in rs]
            have = [m for m in ms if m is not None]
            steps = mean(m.episode_steps for m in have) if have else float("nan")
            lat = [x for m in have for x in m.recovery_latency_steps]
            print(f"| {cond} | {p} | {method} | {len(rs)} | {format_rate(sum(r.success for r in rs), len(rs))} | "
                  f"{steps:.0f} | {mean(r.sim_time for r in rs):.1f} | "
                  f"{mean(m.execution_time_s for m in have) if have else float('nan'):.1f} | "
                  f"{mean(m.modelled_execution_time_s for m in have) if have else float('nan'):.1f} | "
                  f"{mean(m.runtime_reasoning_calls for m in have) if have else float('nan'):.1f} | "
                  f"{sum(m.recoveries for m in have)} | {max(lat) if lat else '-'} | {sum(1 for r in rs if r.error)} |")


if __name__ == "__main__":
    main()
