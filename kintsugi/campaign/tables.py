"""The paper's tables computed from trial records, as plain `TextTable`s (render.py draws them).

Conventions, chosen to match Tables II–III of the contact-formation paper:
- A trial with `error` counts as a failure for F and G and in the errors column;
  it is left out of the extra-execution means (it never ran its course).
- Extra executions show "—" for a method none of whose trials ever recorded a
  nonzero extra execution: a baseline without recovery (the paper's "—"), while a
  recovery method that needed none in one condition still shows 0.0.
- Table III pools each (method, variant) over conditions, as the paper shows one
  matrix per peg shape; rows are the skill that failed, columns the first skill
  of its recovery plan, row percentages with counts.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Iterable, Sequence

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.stats import fmt, format_rate, mean, median, ratio
from kintsugi.core.record import TrialRecord

CONTACT_FORMATIONS = ("fit", "align", "insert")

Cell = tuple[str, str, str]


@dataclass
class TextTable:
    """A rendered-agnostic table: strings only, so console, Markdown and HTML agree."""

    title: str
    columns: list[str]
    rows: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _cell(r: TrialRecord) -> Cell:
    return (r.method, r.variant, r.condition)


def group_by_cell(records: Iterable[TrialRecord], cfg: CampaignConfig | None = None) -> dict[Cell, list[TrialRecord]]:
    """Records per (method, variant, condition): config order first, then cells only the records know."""
    groups: dict[Cell, list[TrialRecord]] = {c: [] for c in (cfg.cells() if cfg else [])}
    for r in records:
        groups.setdefault(_cell(r), []).append(r)
    return {c: rs for c, rs in groups.items() if rs}


def _ordered_skills(seen: Iterable[str]) -> list[str]:
    seen = set(seen)
    return [s for s in CONTACT_FORMATIONS if s in seen] + sorted(seen - set(CONTACT_FORMATIONS))


def _recovering_methods(records: Sequence[TrialRecord]) -> set[str]:
    """Methods that showed recovery in any trial: an extra execution or a recovery transition."""
    return {r.method for r in records if r.transitions or any(v > 0 for v in r.extra_executions.values())}


def table_ii(
    records: Sequence[TrialRecord],
    cfg: CampaignConfig | None = None,
    recovering: set[str] | None = None,
) -> TextTable:
    """Success F/G with Wilson 95% intervals and mean extra executions per contact formation.

    `recovering` names the methods that have recovery (their extra executions show
    numbers even when all zero); by default it is inferred from the records.
    """
    skills = _ordered_skills(k.lower() for r in records for k in r.extra_executions)
    recovering = _recovering_methods(records) if recovering is None else recovering
    table = TextTable(
        title="Table II — success and extra executions per cell",
        columns=["Method", "Variant", "Condition", "n", *[s.capitalize() for s in skills],
                 "F % [95% CI]", "G % [95% CI]", "F+G-", "F-G+", "Err"],
        notes=[
            "Fit/Align/Insert: mean extra executions per trial caused by recovery (trials without error); "
            "— for methods that never recovered.",
            "F: success by the method's own verdict, G: ground-truth success, as % [Wilson 95% interval]. "
            "F+G-: false successes (the method claimed success, the peg was not in); F-G+: missed successes. "
            "Err: trials that raised or crashed; they count as failures.",
        ],
    )
    for (method, variant, condition), rs in group_by_cell(records, cfg).items():
        n = len(rs)
        ok = [r for r in rs if r.error is None]
        extra = [
            fmt(mean(_lower(r.extra_executions).get(s, 0) for r in ok)) if method in recovering else "—"
            for s in skills
        ]
        f = sum(r.framework_success and r.error is None for r in rs)
        g = sum(r.success and r.error is None for r in rs)
        false_ok = sum(r.framework_success and not r.success for r in ok)
        missed = sum(r.success and not r.framework_success for r in ok)
        table.rows.append([method, variant, condition, str(n), *extra,
                           format_rate(f, n), format_rate(g, n), str(false_ok), str(missed), str(n - len(ok))])
    return table


def _lower(d: dict[str, int]) -> dict[str, int]:
    return {k.lower(): v for k, v in d.items()}


def transition_counts(records: Iterable[TrialRecord]) -> Counter[tuple[str, str]]:
    """(failed skill, first recovery skill) -> count over the given trials."""
    return Counter((a.lower(), b.lower()) for r in records for a, b in r.transitions)


def table_iii(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[TextTable]:
    """One transition matrix per (method, variant) with any transitions, pooled over conditions."""
    pooled: dict[tuple[str, str], list[TrialRecord]] = {}
    for (method, variant, _), rs in group_by_cell(records, cfg).items():
        pooled.setdefault((method, variant), []).extend(rs)
    tables = []
    for (method, variant), rs in pooled.items():
        counts = transition_counts(rs)
        if not counts:
            continue
        skills = _ordered_skills([a for a, _ in counts] + [b for _, b in counts] + list(CONTACT_FORMATIONS))
        table = TextTable(
            title=f"Table III — recovery transitions, {method} / {variant} (pooled over conditions)",
            columns=["From \\ To", *[s.capitalize() for s in skills], "n"],
            notes=["Row: the skill that failed; column: the first skill of its recovery plan. "
                   "Row percentages with counts."],
        )
        for src in skills:
            total = sum(counts[(src, dst)] for dst in skills)
            cells = [
                f"{100 * counts[(src, dst)] / total:.1f}% ({counts[(src, dst)]})" if total else "—"
                for dst in skills
            ]
            table.rows.append([src.capitalize(), *cells, str(total)])
        tables.append(table)
    return tables


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


def all_tables(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[TextTable]:
    """Table II, every Table III matrix, and the cost table, in report order."""
    return [table_ii(records, cfg), *table_iii(records, cfg), timing_table(records, cfg)]
