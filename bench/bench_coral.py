"""CoRAL campaign figures from recorded trials: success with Wilson CI, attempts, cost-code share of the MPPI
step, and the physics error of the priors and of the beliefs after each refinement cycle.

Reads the `results.jsonl` of one or more `kintsugi bench` campaign directories (run the campaign first, e.g.
`kintsugi bench push-force --methods coral,l2r --conditions all --trials 10 --workers 1
--set coral.memory_path=runs/mem.sqlite`). Errors are |belief - truth| / truth of the task's target object;
the truth comes from the record's drawn parameters (`<object>.mass_kg`, `<object>.friction`), read here only
to score. Last line: one JSON object with the per-(task, method) figures.
Usage: .venv/bin/python bench/bench_coral.py DIR [DIR ...]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_mppi import machine  # noqa: E402
from kintsugi.campaign.stats import format_rate  # noqa: E402
from kintsugi.core.record import TrialRecord


def _errors(beliefs: dict | None, params: dict, obj: str) -> tuple[float, float] | None:
    if not beliefs or obj not in beliefs or f"{obj}.mass_kg" not in params:
        return None
    b = beliefs[obj]
    m, f = params[f"{obj}.mass_kg"], params[f"{obj}.friction"]
    return abs(b["mass_kg"] - m) / m, abs(b["friction"] - f) / f


def summarize(records: list[TrialRecord]) -> dict:
    cells: dict[tuple[str, str], list[TrialRecord]] = defaultdict(list)
    for r in records:
        cells[(r.task, r.method)].append(r)
    out = {}
    for (task, method), recs in sorted(cells.items()):
        obj = "board" if "board" in task else "box"
        k = sum(r.success for r in recs)
        attempts, code, mppi, errs = [], [], [], defaultdict(list)
        for r in recs:
            m = r.details.get("method", {}) if isinstance(r.details, dict) else {}
            tries = m.get("attempts", [])
            attempts.append(len(tries))
            for i, a in enumerate(tries):
                if a.get("code_ms_per_step") is not None and a.get("mppi_ms_per_step"):
                    code.append(a["code_ms_per_step"])
                    mppi.append(a["mppi_ms_per_step"])
                e = _errors(a.get("beliefs_before"), r.params, obj)
                if e:
                    errs[i].append(e)
        cell = {"trials": len(recs), "successes": k, "rate": format_rate(k, len(recs)),
                "mean_attempts": round(sum(attempts) / max(1, len(attempts)), 2),
                "errors": sum(r.error is not None for r in recs)}
        if code:
            cell["code_ms_per_step"] = round(sum(code) / len(code), 3)
            cell["mppi_ms_per_step"] = round(sum(mppi) / len(mppi), 1)
            cell["code_share"] = round(sum(code) / sum(mppi), 4)
        if errs:
            cell["belief_error_by_attempt"] = {
                str(i + 1): {"n": len(v), "mass": round(sum(a for a, _ in v) / len(v), 3),
                             "friction": round(sum(b for _, b in v) / len(v), 3)} for i, v in sorted(errs.items())}
        out[f"{task}/{method}"] = cell
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    args = ap.parse_args()
    records = []
    for d in args.dirs:
        path = d / "results.jsonl" if d.is_dir() else d
        records += [TrialRecord.model_validate_json(x) for x in path.read_text().splitlines() if x.strip()]
    figures = summarize(records)
    print(f"machine: {machine()}")
    print(f"{'task/method':36s} {'success':>22s} {'attempts':>8s} {'code/MPPI step':>18s}  belief error (mass, friction) "
          f"by attempt")
    for key, c in figures.items():
        share = f"{c.get('code_ms_per_step', 0):.2f}/{c.get('mppi_ms_per_step', 0):.0f} ms" if "code_share" in c else "-"
        errs = " ".join(f"#{i}:{e['mass']:.0%},{e['friction']:.0%}" for i, e in c.get("belief_error_by_attempt",
                                                                                    {}).items())
        print(f"{key:36s} {c['rate']:>22s} {c['mean_attempts']:>8.2f} {share:>18s}  {errs}")
    print(json.dumps(figures))


if __name__ == "__main__":
    main()
