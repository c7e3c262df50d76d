"""Fresh seeds beside the development seeds: which headline figures moved, and by how much.

A headline table is measured on the seeds development looked at; the same campaign on a seed block no
development run touched (`--base-seed 10000`) says whether the figures hold. This script reads the fresh
campaigns and the development figures (campaign directories, or the Markdown table a benchmark page
already shows), prints a cell-by-cell comparison and a short summary of what moved, and with `--page`
writes both into a block of the benchmark page (`bench/pages.py` writes the block, with the command,
date, commit and machine).

    .venv/bin/python bench/fresh.py FRESH_DIR... (--dev DIR... | --dev-table PAGE "HEADING TEXT")
        [--figure success|steps] [--tables] [--page PAGE --name BLOCK]

Success is the ground-truth success rate with its Wilson 95 % interval; a cell "moved" when the rate
differs by a whole percentage point or more, and the summary names the cells whose fresh rate lies outside the development interval.
`--figure steps` also compares the mean episode steps (System B's `method_figures.episode_steps`) and the
disturbances per trial (the event logs' drops and pushes: how hard the seeds were).
With `--dev-table` the development figures are read from the first Markdown table under the heading
line that contains HEADING TEXT: its `method`, `task`, `shape`/`variant` and `condition` columns name
the cell (a missing column matches every value), and the first column whose header contains `G %` or
`success %` gives `rate [low–high]`; a table with a `task` column and one column per method instead (cells
`k/n [low–high]`, System C's) gives one cell per task and method.
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kintsugi.campaign.stats import mean, wilson_interval  # noqa: E402

KEYS = ("task", "method", "variant", "condition")
_RATE = re.compile(r"(\d+(?:\.\d+)?)\s*\[(\d+(?:\.\d+)?)\s*[–-]\s*(\d+(?:\.\d+)?)\]")


@dataclass
class Figure:
    """One cell's figures: success k of n (or a rate read from a page) and mean steps when known."""

    rate: float  # percent
    low: float
    high: float
    n: int | None = None
    k: int | None = None
    steps: float | None = None
    disturbances: float | None = None  # mean disturbance events per trial (drops, pushes), from the event logs

    def text(self) -> str:
        head = f"{self.rate:.0f} [{self.low:.0f}–{self.high:.0f}]"
        return head + (f" ({self.k}/{self.n})" if self.n is not None else "")


def campaign_cells(dirs: list[str]) -> dict[tuple, Figure]:
    """{(task, method, variant, condition): Figure} over the campaigns' planned trials (a key seen twice counts once)."""
    from kintsugi.campaign.plan import expand
    from kintsugi.campaign.store import ResultStore

    seen: dict[str, object] = {}
    cells: dict[tuple, list] = {}  # in the campaigns' plan order
    for d in dirs:
        store = ResultStore(d)
        specs = expand(store.load_config())
        for s in specs:
            cells.setdefault(tuple(getattr(s, k) for k in KEYS), [])
        wanted = {s.key for s in specs}
        for r in store.read():
            if r.key in wanted and r.key not in seen:
                seen[r.key] = r
                cells[tuple(getattr(r, k) for k in KEYS)].append(r)
    out = {}
    for key, rs in cells.items():
        if not rs:
            continue
        k = sum(bool(r.success) and r.error is None for r in rs)
        low, high = wilson_interval(k, len(rs))
        steps = [r.method_figures["episode_steps"] for r in rs if "episode_steps" in r.method_figures]
        out[key] = Figure(100 * k / len(rs), 100 * low, 100 * high, len(rs), k, mean(steps) if steps else None,
                          mean(sum(e.kind == "disturbance" for e in r.events) for r in rs))
    return out


def _cells(line: str) -> list[str]:
    return [c.strip().strip("*").strip() for c in line.strip().strip("|").split("|")]


def page_cells(page: str, heading: str) -> dict[tuple, Figure]:
    """The development figures of the first Markdown table under the line containing `heading`."""
    lines = Path(page).read_text().splitlines()
    start = next((i for i, line in enumerate(lines) if heading in line), None)
    if start is None:
        raise SystemExit(f"{page} has no line containing {heading!r}")
    rows = []
    for line in lines[start + 1:]:
        if line.startswith("|"):
            rows.append(_cells(line))
        elif rows:
            break
    if len(rows) < 3:
        raise SystemExit(f"{page}: no Markdown table under {heading!r}")
    header = [h.lower() for h in rows[0]]
    col = {name: next((i for i, h in enumerate(header) if h in alias), None)
           for name, alias in (("task", ("task",)), ("method", ("method",)), ("variant", ("shape", "variant")),
                               ("condition", ("condition",)))}
    rate_col = next((i for i, h in enumerate(header) if "g %" in h or "success %" in h), None)
    steps_col = next((i for i, h in enumerate(header) if h == "steps"), None)
    if col["method"] is None and rate_col is None and col["task"] is not None:
        return _wide_cells(rows, header, col["task"])
    if (col["method"] is None and col["task"] is None) or rate_col is None:
        raise SystemExit(f"{page}: the table under {heading!r} needs a method or task column and a `G %` or "
                         "`success %` one, or a task column and one column per method")
    out = {}
    for row in rows[2:]:
        m = _RATE.search(row[rate_col]) if rate_col < len(row) else None
        if not m:
            continue
        key = tuple(row[col[k]] if col[k] is not None else None for k in KEYS)
        steps = float(row[steps_col]) if steps_col is not None and re.fullmatch(r"[\d.]+", row[steps_col]) else None
        out[key] = Figure(float(m[1]), float(m[2]), float(m[3]), steps=steps)
    return out


_FRACTION = re.compile(r"(\d+)/(\d+)")


def _wide_cells(rows: list[list[str]], header: list[str], task_col: int) -> dict[tuple, Figure]:
    """A table with one row per task and one column per method (System C's), its cells `k/n [low–high]` or
    `k/n`: the method is the column's header, the task the row's first word (`flip-box (T5)` is flip-box)."""
    out = {}
    for row in rows[2:]:
        task = row[task_col].split(" (")[0].strip()
        for i, cell in enumerate(row):
            m = _FRACTION.match(cell)
            if i == task_col or not m or int(m[2]) == 0:
                continue
            k, n = int(m[1]), int(m[2])
            low, high = wilson_interval(k, n)
            method = re.split(r" [(\[]", header[i])[0].strip()  # `expert-fsm [95 % CI]` is expert-fsm
            out[(task, method, None, None)] = Figure(100 * k / n, 100 * low, 100 * high, n, k)
    return out


def _match(dev: dict[tuple, Figure], key: tuple) -> Figure | None:
    for dkey, fig in dev.items():
        if all(d is None or d == k for d, k in zip(dkey, key)):
            return fig
    return None


def compare(fresh: dict[tuple, Figure], dev: dict[tuple, Figure], steps: bool = False) -> list[str]:
    """Markdown: the cell-by-cell table, then the summary of what moved."""
    shown = [k for k in KEYS if len({key[KEYS.index(k)] for key in fresh}) > 1] or ["method"]
    head = [*shown, "development", "fresh seeds", "change"] + (
        ["steps: dev → fresh", "disturbances per trial: dev → fresh"] if steps else [])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    moved, outside, unmatched, n_total, k_total = [], [], [], 0, 0
    for key, f in fresh.items():
        d = _match(dev, key)
        name = "/".join(str(key[KEYS.index(k)]) for k in shown)
        n_total, k_total = n_total + (f.n or 0), k_total + (f.k or 0)
        if d is None:
            unmatched.append(name)
            row = [*(str(key[KEYS.index(k)]) for k in shown), "—", f.text(), "—"]
        else:
            delta = round(f.rate) - round(d.rate)  # whole points, as the tables print them
            row = [*(str(key[KEYS.index(k)]) for k in shown), d.text(), f.text(), f"{delta:+.0f} pp" if delta else "0"]
            if delta:
                moved.append((abs(delta), name, d, f, delta))
            if not d.low <= f.rate <= d.high:
                outside.append(name)
        if steps:
            ds = f"{d.steps:.0f}" if d is not None and d.steps is not None else "—"
            row.append(f"{ds} → {f.steps:.0f}" if f.steps is not None else "—")
            dd = f"{d.disturbances:.2f}" if d is not None and d.disturbances is not None else "—"
            row.append(f"{dd} → {f.disturbances:.2f}")
        lines.append("| " + " | ".join(row) + " |")
    low, high = wilson_interval(k_total, n_total) if n_total else (0.0, 1.0)
    lines += ["", "**What moved on the fresh seeds:**",
              f"- {len(fresh)} cell{'' if len(fresh) == 1 else 's'}, {n_total} fresh trials, {k_total} successes overall "
              f"({100 * k_total / max(n_total, 1):.0f} % [{100 * low:.0f}–{100 * high:.0f}])."]
    if not moved:
        lines.append("- No success rate moved.")
    for _, name, d, f, delta in sorted(moved, key=lambda m: (-m[0], m[1])):
        lines.append(f"- {name}: {d.rate:.0f} % → {f.rate:.0f} % ({delta:+.0f} points; fresh {f.text()})"
                     + ("" if d.low <= f.rate <= d.high else ", outside the development interval"))
    same = len(fresh) - len(moved) - len(unmatched)
    lines.append(f"- {same} cell{'' if same == 1 else 's'} unchanged; {len(outside)} outside the "
                 f"development interval" + (f" ({', '.join(outside)})" if outside else "") + ".")
    if unmatched:
        lines.append(f"- No development figure for: {', '.join(unmatched)}.")
    return lines


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="bench/fresh.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("fresh", nargs="+", help="campaign directories on the fresh seed block")
    ap.add_argument("--dev", nargs="+", default=[], help="campaign directories on the development seeds")
    ap.add_argument("--dev-table", nargs=2, metavar=("PAGE", "HEADING"),
                    help="read the development figures from the Markdown table under HEADING in PAGE")
    ap.add_argument("--figure", choices=("success", "steps"), default="success")
    ap.add_argument("--tables", action="store_true", help="also write the fresh campaigns' full system tables")
    ap.add_argument("--page", help="benchmark page to write into")
    ap.add_argument("--name", help="the page's block name (required with --page)")
    args = ap.parse_args(argv)
    if bool(args.dev) == bool(args.dev_table):
        ap.error("give the development figures as --dev DIR... or --dev-table PAGE HEADING (one of them)")
    if args.page and not args.name:
        ap.error("--page needs --name BLOCK")
    try:
        from bench.pages import Block, campaign_tables, command_line, write_block
    except ModuleNotFoundError:  # run as a script: bench/ is on the path
        from pages import Block, campaign_tables, command_line, write_block

    dev = campaign_cells(args.dev) if args.dev else page_cells(*args.dev_table)
    fresh = campaign_cells(args.fresh)
    source = (f"development campaigns {', '.join(f'`{d}`' for d in args.dev)}" if args.dev
              else f"the development table under “{args.dev_table[1]}” in `{args.dev_table[0]}`")
    lines = [f"Fresh campaigns {', '.join(f'`{d}`' for d in args.fresh)} against {source}.", "",
             *compare(fresh, dev, steps=args.figure == "steps")]
    print("\n".join(lines))
    if args.tables:
        lines += ["", *[line for d in args.fresh for line in campaign_tables(d)]]
    if args.page:
        print(f"page: {write_block(args.page, Block(args.name, command_line(), lines))}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
