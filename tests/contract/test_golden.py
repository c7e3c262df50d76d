"""The golden trials replay record for record (bench/golden.py's check, one trial per test so xdist shares them).

Three systems, two methods each, three seeds, with drops and recoveries: whatever the substrate's shape,
the trials it runs stay the same. Re-capture only for an intended change of behaviour (`bench/golden.py --write`).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[2] / "bench" / "golden.py"
_spec = importlib.util.spec_from_file_location("bench_golden", _PATH)
golden = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(golden)

LINES = golden.GOLDEN.read_text().splitlines()


def test_the_golden_set_covers_three_systems_two_methods_three_seeds() -> None:
    specs = [json.loads(line)["spec"] for line in LINES]
    by_task: dict[str, set[str]] = {}
    for s in specs:
        by_task.setdefault(s["task"], set()).add(s["method"])
    assert len(by_task) == 3 and all(len(m) == 2 for m in by_task.values())
    assert {s["seed"] for s in specs if s["task"] == "pour-single"} == {0, 1, 2}


@pytest.mark.slow
@pytest.mark.parametrize("line", LINES, ids=[json.loads(line)["spec"]["method"] + "-" + json.loads(line)["spec"]["task"]
                                            + "-" + str(json.loads(line)["spec"]["seed"]) for line in LINES])
def test_a_golden_trial_replays_record_for_record(line: str) -> None:
    spec, old = golden._load(line)
    new = golden._run(spec)
    assert golden.differences(old, new) == []


def test_differences_sees_a_changed_field_and_takes_null_for_missing() -> None:
    a = {"success": True, "method_figures": {"x": [1, 2]}, "opt": None}
    assert golden.differences(a, {"success": True, "method_figures": {"x": [1, 2]}}) == []
    assert golden.differences(a, {"success": False, "method_figures": {"x": [1, 3]}, "opt": None}) == [
        "method_figures.x[1]: 2 -> 3", "success: True -> False"]


def test_without_timings_drops_wall_clock_figures() -> None:
    from kintsugi.core.record import TrialRecord

    r = TrialRecord(key="t/m/v/c/0", task="t", method="m", variant="v", condition="c", seed=0,
                    method_figures={"attempts": [{"code_ms_per_step": 2.5, "reached": True}], "plan_wall_s": 1.0})
    assert r.without_timings()["method_figures"] == {"attempts": [{"reached": True}]}
