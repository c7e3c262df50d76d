"""Replay the golden trials and compare them record for record with `tests/data/golden/records.jsonl`.

The golden set covers the three systems, two methods each, three seeds, with drops and recoveries:
the substrate may change shape, the trials it runs may not. Records are compared without their
wall-clock fields (`TrialRecord.without_timings`); old-format golden records load through the
record's own migration, so this also proves that old results files still read.

    bench/golden.py            # check: exits 1 and prints the first differences
    bench/golden.py --write    # re-capture (only when a change of behaviour is intended)
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

GOLDEN = Path(__file__).resolve().parents[1] / "tests" / "data" / "golden" / "records.jsonl"


def _run(spec: dict) -> dict:
    from kintsugi.core.record import TrialSpec
    from kintsugi.core.runner import run_trial

    return run_trial(TrialSpec(**spec)).without_timings()


def _load(line: str) -> tuple[dict, dict]:
    from kintsugi.core.record import TrialRecord

    item = json.loads(line)
    old = TrialRecord.model_validate(item["record"]).without_timings()
    # Corrected on purpose: reasoning calls and errors are counted from the transcript for every system
    # (contact records used to say 0 calls while their transcript held the priors and formulation calls).
    old["reasoning_calls"] = len(old["transcript"])
    old["reasoning_errors"] = sum(1 for c in old["transcript"] if c.get("error"))
    return item["spec"], old


def differences(old: object, new: object, where: str = "") -> list[str]:
    """Dotted paths where two JSON values differ (floats to 1e-9 relative)."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for k in sorted(set(old) | set(new)):
            if old.get(k) is None and new.get(k) is None:
                continue  # a missing optional field and a null one are the same
            out += differences(old.get(k, "<missing>"), new.get(k, "<missing>"), f"{where}.{k}" if where else k)
        return out
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return [f"{where}: {len(old)} items -> {len(new)}"]
        return [d for i, (a, b) in enumerate(zip(old, new)) for d in differences(a, b, f"{where}[{i}]")]
    if isinstance(old, float) and isinstance(new, (int, float)) and not isinstance(new, bool):
        return [] if abs(old - new) <= 1e-9 * max(1.0, abs(old)) else [f"{where}: {old} -> {new}"]
    return [] if old == new else [f"{where}: {str(old)[:80]} -> {str(new)[:80]}"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="re-capture the golden records")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    lines = GOLDEN.read_text().splitlines()
    pairs = [_load(line) for line in lines]
    with ProcessPoolExecutor(args.workers) as pool:
        fresh = list(pool.map(_run, [spec for spec, _ in pairs]))
    if args.write:
        GOLDEN.write_text("".join(json.dumps({"spec": s, "record": r}) + "\n" for (s, _), r in zip(pairs, fresh)))
        print(f"wrote {len(fresh)} golden records to {GOLDEN}")
        return 0
    bad = 0
    for (spec, old), new in zip(pairs, fresh):
        diffs = differences(old, new)
        if diffs:
            bad += 1
            print(f"DIFFERS {old['key']}: {len(diffs)} fields; first: " + "; ".join(diffs[:6]))
    print(f"golden: {len(pairs) - bad} of {len(pairs)} trials replay record for record")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
