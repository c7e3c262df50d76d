"""Write docs/configuration.md from the typed configs: every task's settings, every method's, the reasoner's.

    .venv/bin/python docs/tools/configuration.py          # rewrite docs/configuration.md
    .venv/bin/python docs/tools/configuration.py --check  # exit 1 if it is out of date (the tests run this)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from pydantic import BaseModel

OUT = Path(__file__).resolve().parents[1] / "configuration.md"


def _rows(model: type[BaseModel], prefix: str, value: Any) -> list[tuple[str, str, str]]:
    """(dotted key, default, description) for every leaf of a config model."""
    rows = []
    for name, field in model.model_fields.items():
        key = f"{prefix}{name}"
        sub = field.annotation
        current = getattr(value, name)
        if isinstance(current, BaseModel):
            rows += _rows(type(current), key + ".", current)
            continue
        default = json.dumps(value.model_dump(mode="json")[name], default=str)
        text = (field.description or "").replace("\n", " ").replace("|", "\\|")
        rows.append((key, default.replace("|", "\\|"), text))
        del sub
    return rows


def _table(rows: list[tuple[str, str, str]]) -> list[str]:
    out = ["| key | default | meaning |", "|---|---|---|"]
    out += [f"| `{k}` | `{d}` | {t} |" for k, d, t in rows]
    return out


def render() -> str:
    import kintsugi  # noqa: F401 - headless rendering before mujoco loads
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.core.registry import METHODS, TASKS

    load_builtins()
    lines = ["# Configuration reference", "",
             "Generated from the typed configs by `docs/tools/configuration.py`; a test checks it is current.",
             "Every key is set with `--set <key>=<value>` on `run`, `bench`, `graph` and `config`, or in a",
             "`--config` file (the layout `kintsugi config <task>` prints). Method settings are `method.<key>`",
             "(every method of the run) or `methods.<name>.<key>` (one method); reasoner settings `reasoner.<key>`.",
             "An unknown key or a bad value is a one-line error naming the key.", "", "## Tasks", ""]
    first_of: dict[type, tuple[str, list]] = {}
    for entry in sorted(TASKS, key=lambda e: e.name):
        task = entry.factory()
        cfg = task.config({})
        rows = _rows(type(cfg), "", cfg)
        lines += [f"### `{entry.name}`", "", entry.description, "",
                  f"Conditions: {', '.join(f'`{c}`' for c in task.conditions)}. "
                  f"Methods: {', '.join(f'`{m.name}`' for m in METHODS if task.method_tag in m.tags)}.", ""]
        if type(cfg) not in first_of:
            first_of[type(cfg)] = (entry.name, rows)
            lines += _table(rows) + [""]
            continue
        base, base_rows = first_of[type(cfg)]  # tasks of one world share most settings: show what differs
        same = set(base_rows)
        diff = [r for r in rows if r not in same]
        gone = sorted({r[0] for r in base_rows} - {r[0] for r in rows})
        lines += [f"The settings of `{base}`" + (", except:" if diff or gone else "."), ""]
        if diff:
            lines += _table(diff) + [""]
        if gone:
            lines += ["Without " + ", ".join(f"`{k}`" for k in gone) + ".", ""]
    lines += ["## Methods", ""]
    for entry in sorted(METHODS, key=lambda e: e.name):
        lines += [f"### `{entry.name}`", "", entry.description, ""]
        settings = entry.config() if entry.config is not None else None
        rows = _rows(type(settings), "method.", settings) if settings is not None else []
        lines += (_table(rows) if rows else ["No settings."]) + [""]
    lines += ["## Reasoner", "", "Set with `reasoner.<key>` (`reasoner.options.<key>` for a backend's own).", ""]
    lines += _table(_rows(ReasonerSettings, "reasoner.", ReasonerSettings())) + [""]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    text = render()
    if "--check" in argv:
        if not OUT.exists() or OUT.read_text() != text:
            print(f"{OUT} is out of date: run .venv/bin/python docs/tools/configuration.py", file=sys.stderr)
            return 1
        return 0
    OUT.write_text(text)
    print(f"wrote {OUT} ({len(text.splitlines())} lines)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
