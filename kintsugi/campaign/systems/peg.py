"""System A's tables (the contact-formation paper's Tables II and III) from peg trial records.

Conventions, chosen to match the paper:
- A trial with `error` counts as a failure for F and G and in the errors column;
  it is left out of the extra-execution means (it never ran its course).
- Extra executions come from the record's `PegFigures`. They show "—" for a method none of
  whose trials ever recorded a nonzero extra execution or a recovery transition: a baseline
  without recovery (the paper's "—"), while a recovery method that needed none in one
  condition still shows 0.0.
- Table III pools each (method, variant) over conditions, as the paper shows one matrix per
  peg shape; rows are the skill that failed, columns the first skill of its recovery plan,
  row percentages with counts.
"""

from __future__ import annotations

from collections import Counter
from typing import Iterable, Sequence

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.stats import fmt, format_rate, mean
from kintsugi.campaign.tables import TextTable, group_by_cell
from kintsugi.core.record import TrialRecord
from kintsugi.methods.recovery.skill_log import RECOVERY_SKILLS, PegFigures

CONTACT_FORMATIONS = RECOVERY_SKILLS


def extra_executions(record: TrialRecord) -> dict[str, int]:
    """The trial's extra executions per skill (lower-case names); empty for a record without `PegFigures`."""
    figures = PegFigures.of(record)
    return {k.lower(): v for k, v in figures.extra_executions.items()} if figures else {}


def ordered_skills(seen: Iterable[str]) -> list[str]:
    """The contact formations in their order, then any other skill names alphabetically."""
    seen = set(seen)
    return [s for s in CONTACT_FORMATIONS if s in seen] + sorted(seen - set(CONTACT_FORMATIONS))


def recovering_methods(records: Sequence[TrialRecord]) -> set[str]:
    """Methods that showed recovery in any trial: an extra execution or a recovery transition."""
    return {r.method for r in records if r.transitions or any(v > 0 for v in extra_executions(r).values())}


def table_ii(
    records: Sequence[TrialRecord],
    cfg: CampaignConfig | None = None,
    recovering: set[str] | None = None,
) -> TextTable:
    """Success F/G with Wilson 95% intervals and mean extra executions per contact formation.

    `recovering` names the methods that have recovery (their extra executions show
    numbers even when all zero); by default it is inferred from the records.
    """
    extras = {id(r): extra_executions(r) for r in records}
    skills = ordered_skills(k for e in extras.values() for k in e)
    recovering = recovering_methods(records) if recovering is None else recovering
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
        extra = [fmt(mean(extras[id(r)].get(s, 0) for r in ok)) if method in recovering else "—" for s in skills]
        f = sum(r.framework_success for r in ok)
        g = sum(r.success for r in ok)
        false_ok = sum(r.framework_success and not r.success for r in ok)
        missed = sum(r.success and not r.framework_success for r in ok)
        table.rows.append([method, variant, condition, str(n), *extra,
                           format_rate(f, n), format_rate(g, n), str(false_ok), str(missed), str(n - len(ok))])
    return table


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
        skills = ordered_skills([a for a, _ in counts] + [b for _, b in counts] + list(CONTACT_FORMATIONS))
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


def system_tables(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[TextTable]:
    """Table II, then every Table III matrix (the `peg` system's own tables)."""
    return [table_ii(records, cfg), *table_iii(records, cfg)]
