"""CoRAL campaign figures from recorded trials: system C's Table I as `kintsugi bench` prints it (success with
Wilson CI, attempts, the cost code's share of the MPPI step, where the cost came from, and the physics error of
the beliefs each attempt planned with), from `kintsugi/campaign/systems/contact.py`.

Reads the `results.jsonl` of one or more `kintsugi bench` campaign directories (run the campaign first, e.g.
`kintsugi bench push-force --methods coral,l2r --conditions all --trials 10 --workers 1
--set coral.memory_path=runs/mem.sqlite`). Errors are |belief - truth| / truth of the task's target object;
the truth comes from the record's drawn parameters (`<object>.mass_kg`, `<object>.friction`), read only to
score. Last line: one JSON object with the per-(task, method) figures.
Usage: .venv/bin/python bench/bench_coral.py DIR [DIR ...]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from rich.console import Console  # noqa: E402

from bench_mppi import machine  # noqa: E402
from kintsugi.campaign.render import print_tables  # noqa: E402
from kintsugi.campaign.tables import tables_for  # noqa: E402
from kintsugi.core.plugins import load_builtins  # noqa: E402
from kintsugi.core.record import TrialRecord  # noqa: E402
from kintsugi.campaign.systems.contact import summarize  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    ap.add_argument("--page", help="also write the tables into this benchmark page (docs/benchmarks-coral.md)")
    args = ap.parse_args()
    records = []
    for d in args.dirs:
        path = d / "results.jsonl" if d.is_dir() else d
        records += [TrialRecord.model_validate_json(x) for x in path.read_text().splitlines() if x.strip()]
    load_builtins()  # the contact tasks name their target objects
    print(f"machine: {machine()}")
    console = Console()
    for task in dict.fromkeys(r.task for r in records):
        console.print(f"## {task}")
        print_tables(tables_for(task, [r for r in records if r.task == task]), console)
    print(json.dumps(summarize(records)))
    if args.page:
        try:
            from bench.pages import Block, command_line, table_lines, write_block
        except ModuleNotFoundError:  # run as a script: bench/ is on the path
            from pages import Block, command_line, table_lines, write_block
        lines = [line for task in dict.fromkeys(r.task for r in records)
                 for line in (f"#### {task}", "", *table_lines(tables_for(task, [r for r in records if r.task == task])))]
        print(f"page: {write_block(args.page, Block('bench_coral', command_line(), lines))}")


if __name__ == "__main__":
    main()
