"""A campaign's tables as plain `TextTable`s (render.py draws them): each system's own, then the generic ones.

`tables_for(task or system, records, cfg)` picks the tables by the task's `system` attribute
(`peg`, `tabletop`, `contact`, or whatever a plugin registers with `register_tables`) and always
adds the generic success table and the cost table. A task of no known system gets the generic
tables only. The built-in systems' own tables (`kintsugi/campaign/systems/`) are imported only when a
campaign of that system is tabulated.

Conventions shared by every table:
- Cells are (method, variant, condition), in config order first, then cells only the records know.
- A trial with `error` counts as a failure and in the errors column.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.stats import fmt, format_rate, mean, median, ratio
from kintsugi.core.record import TrialRecord

Cell = tuple[str, str, str]


@dataclass
class TextTable:
    """A rendered-agnostic table: strings only, so console, Markdown and HTML agree."""

    title: str
    columns: list[str]
    rows: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


TableBuilder = Callable[[Sequence[TrialRecord], "CampaignConfig | None"], list[TextTable]]

_BUILDERS: dict[str, TableBuilder | str] = {
    "peg": "kintsugi.campaign.systems.peg:system_tables",
    "tabletop": "kintsugi.campaign.systems.tabletop:system_tables",
    "contact": "kintsugi.campaign.systems.contact:system_tables",
}
"""System -> its tables' builder, or "module:function" imported on first use."""


def register_tables(system: str, builder: TableBuilder) -> None:
    """Give a system (e.g. a plugin's own) its tables; a task with `system = <name>` then gets them."""
    _BUILDERS[system] = builder


def _builder(system: str) -> TableBuilder | None:
    found = _BUILDERS.get(system)
    if isinstance(found, str):
        module, name = found.split(":")
        found = _BUILDERS[system] = getattr(importlib.import_module(module), name)
    return found


def system_of(name: str, cfg: CampaignConfig | None = None) -> str | None:
    """The system whose tables fit `name`: a system's own name, or a registered task's `system`
    attribute (its plugins loaded from `cfg`). None for a task of no system or one that is not known."""
    if name in _BUILDERS:
        return name
    from kintsugi.campaign.bootstrap import bootstrap
    from kintsugi.core.errors import KintsugiError
    from kintsugi.core.registry import TASKS

    try:
        bootstrap(list(cfg.plugins) if cfg else [], name)
        return getattr(TASKS.get(name).factory(), "system", None)
    except KintsugiError:
        return None


def tables_for(name: str, records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[TextTable]:
    """The system's own tables (by task name or system name), then the generic success and cost tables."""
    system = system_of(name, cfg)
    builder = _builder(system) if system else None
    own = builder(records, cfg) if builder else []
    return [*own, success_table(records, cfg), timing_table(records, cfg)]


def _cell(r: TrialRecord) -> Cell:
    return (r.method, r.variant, r.condition)


def group_by_cell(records: Iterable[TrialRecord], cfg: CampaignConfig | None = None) -> dict[Cell, list[TrialRecord]]:
    """Records per (method, variant, condition): config order first, then cells only the records know."""
    groups: dict[Cell, list[TrialRecord]] = {c: [] for c in (cfg.cells() if cfg else [])}
    for r in records:
        groups.setdefault(_cell(r), []).append(r)
    return {c: rs for c, rs in groups.items() if rs}


def successes(rs: Iterable[TrialRecord]) -> int:
    """Ground-truth successes among trials that ran without error."""
    return sum(r.success and r.error is None for r in rs)


def success_table(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> TextTable:
    """Per cell: ground-truth success and the method's own verdict with Wilson 95% intervals."""
    table = TextTable(
        title="Success per cell",
        columns=["Method", "Variant", "Condition", "n", "Success % [95% CI]", "Verdict % [95% CI]",
                 "False succ.", "Err"],
        notes=["Success: the task's scorer (ground truth); Verdict: the method's own claim of success; both as "
               "% [Wilson 95% interval]. False succ.: trials the method called a success that were not. "
               "Err: trials that raised or crashed; they count as failures."],
    )
    for (method, variant, condition), rs in group_by_cell(records, cfg).items():
        n = len(rs)
        ok = [r for r in rs if r.error is None]
        verdict = sum(r.framework_success for r in ok)
        false_ok = sum(r.framework_success and not r.success for r in ok)
        table.rows.append([method, variant, condition, str(n), format_rate(successes(rs), n),
                           format_rate(verdict, n), str(false_ok), str(n - len(ok))])
    return table


def timing_table(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> TextTable:
    """Cost per cell: wall and sim time, physics steps, reasoning calls and latency."""
    table = TextTable(
        title="Cost per cell",
        columns=["Method", "Variant", "Condition", "n", "Wall s", "Sim s",
                 "Steps", "Calls", "s / call", "R.err"],
        notes=["Wall s: median wall time per trial; Sim s, Steps: means per trial; Calls: mean reasoning "
               "calls per trial; s / call: total reasoner latency over total calls; R.err: reasoner errors."],
    )
    for (method, variant, condition), rs in group_by_cell(records, cfg).items():
        calls = sum(r.reasoning_calls for r in rs)
        table.rows.append([
            method, variant, condition, str(len(rs)),
            fmt(median(r.wall_time for r in rs), 2),
            fmt(mean(r.sim_time for r in rs), 2),
            fmt(mean(r.physics_steps for r in rs), 0),
            fmt(mean(r.reasoning_calls for r in rs), 1),
            fmt(ratio(sum(r.reasoning_latency_s for r in rs), calls), 3),
            str(sum(r.reasoning_errors for r in rs)),
        ])
    return table
