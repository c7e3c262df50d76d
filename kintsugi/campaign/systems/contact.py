"""System C's Table I (CoRAL, its ablations and the baselines) from contact trial records.

Per task and method: success x/n and % [Wilson 95% interval], mean attempts, the cost code's share
of an MPPI step, where the cost came from (a formulation or a memory episode), and the physics error
of the beliefs each attempt planned with. Method figures come from the record's `CoralFigures`; a
method that writes none (e.g. the experts) shows "—" for them.

Belief error = |belief - truth| / truth of the task's target object (the registered task's `target`;
for a task not registered in this process, every object the beliefs and the truth both name). The
truth is the trial's drawn parameters (`<object>.mass_kg`, `<object>.friction` in `record.params`):
reading it here is scoring, never given to a method.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from functools import lru_cache
from typing import Any, Sequence

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.stats import format_rate, mean
from kintsugi.campaign.tables import TextTable, group_by_cell, successes
from kintsugi.core.record import TrialRecord
from kintsugi.methods.coral.figures import CoralFigures

DASH = "—"


@lru_cache(maxsize=None)
def target_object(task: str) -> str | None:
    """The registered contact task's target object, None when the task is not registered here."""
    from kintsugi.core.registry import TASKS

    if task not in TASKS:
        return None
    return getattr(getattr(TASKS.get(task).factory(), "spec", None), "target", None)


def belief_error(beliefs: dict[str, Any] | None, params: dict[str, Any], target: str | None) -> tuple[float, float] | None:
    """(mass, friction) relative errors of the beliefs against the trial's truth; None without both."""
    if not beliefs:
        return None
    names = [target] if target else list(beliefs)
    pairs = [(beliefs[o], params[f"{o}.mass_kg"], params[f"{o}.friction"]) for o in names
             if o in beliefs and f"{o}.mass_kg" in params and f"{o}.friction" in params]
    if not pairs:
        return None
    return (mean(abs(b["mass_kg"] - m) / m for b, m, _ in pairs),
            mean(abs(b["friction"] - f) / f for b, _, f in pairs))


def cell_figures(records: Sequence[TrialRecord]) -> dict[str, Any]:
    """One cell's figures: trials, successes, rate, mean attempts, errors, and where measured the cost
    code's time per MPPI step, the cost sources and the belief errors by attempt."""
    n, k = len(records), successes(records)
    attempts: list[int] = []
    code: list[float] = []
    mppi: list[float] = []
    sources: Counter[str] = Counter()
    errs: dict[int, list[tuple[float, float]]] = defaultdict(list)
    for r in records:
        figures = CoralFigures.of(r)
        if figures is None:
            continue
        attempts.append(len(figures.attempts))
        if figures.plan_from:
            sources["memory" if figures.plan_from.startswith("memory") else figures.plan_from] += 1
        for i, a in enumerate(figures.attempts):
            if a.code_ms_per_step is not None and a.mppi_ms_per_step:
                code.append(a.code_ms_per_step)
                mppi.append(a.mppi_ms_per_step)
            e = belief_error(a.beliefs_before, r.params, target_object(r.task))
            if e:
                errs[i].append(e)
    cell: dict[str, Any] = {"trials": n, "successes": k, "rate": format_rate(k, n),
                            "mean_attempts": round(mean(attempts), 2) if attempts else None,
                            "errors": sum(r.error is not None for r in records)}
    if code:
        cell["code_ms_per_step"] = round(mean(code), 3)
        cell["mppi_ms_per_step"] = round(mean(mppi), 1)
        cell["code_share"] = round(sum(code) / sum(mppi), 4)
    if sources:
        cell["cost_source"] = dict(sorted(sources.items()))
    if errs:
        cell["belief_error_by_attempt"] = {
            str(i + 1): {"n": len(v), "mass": round(mean(a for a, _ in v), 3),
                         "friction": round(mean(b for _, b in v), 3)} for i, v in sorted(errs.items())}
    return cell


def summarize(records: Sequence[TrialRecord]) -> dict[str, dict[str, Any]]:
    """`task/method` -> its cell figures, pooled over variants and conditions (a machine-readable summary)."""
    cells: dict[tuple[str, str], list[TrialRecord]] = defaultdict(list)
    for r in records:
        cells[(r.task, r.method)].append(r)
    return {f"{task}/{method}": cell_figures(rs) for (task, method), rs in sorted(cells.items())}


def _errors_text(cell: dict[str, Any], attempt: int) -> str:
    e = cell.get("belief_error_by_attempt", {}).get(str(attempt))
    return f"{e['mass']:.0%}, {e['friction']:.0%} ({e['n']})" if e else DASH


def table_i(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> TextTable:
    """Per task and cell (method, variant, condition): success, attempts, cost code share, cost source, belief errors."""
    groups: dict[tuple[str, str, str, str], list[TrialRecord]] = {}
    for (method, variant, condition), rs in group_by_cell(records, cfg).items():
        for r in rs:
            groups.setdefault((r.task, method, variant, condition), []).append(r)
    cells = {key: cell_figures(rs) for key, rs in groups.items()}
    depth = max((int(i) for c in cells.values() for i in c.get("belief_error_by_attempt", {})), default=0)
    table = TextTable(
        title="Table I — success, attempts, cost code and belief errors per task and method",
        columns=["Task", "Method", "Variant", "Condition", "Success x/n", "% [95% CI]", "Attempts",
                 "Code / MPPI ms per step", "Cost from", *[f"Belief err. #{i} (mass, friction)"
                                                          for i in range(1, depth + 1)], "Err"],
        notes=["Success: ground truth, % [Wilson 95% interval]; a trial with an error counts as a failure. "
               "Attempts: mean MPPI attempts per trial. Code / MPPI: mean cost code time and mean MPPI iteration "
               "per control step (share of the step). Cost from: trials whose cost was formulated / recalled "
               "from memory.",
               "Belief err. #i: mean |belief - truth| / truth of the target's mass and friction the i-th attempt "
               "planned with (trials with that attempt). — : the method records no such figures."],
    )
    for (task, method, variant, condition), c in cells.items():
        share = (f"{c['code_ms_per_step']:.2f} / {c['mppi_ms_per_step']:.0f} ({c['code_share']:.1%})"
                 if "code_share" in c else DASH)
        source = ", ".join(f"{s} {k}" for s, k in c.get("cost_source", {}).items()) or DASH
        attempts = f"{c['mean_attempts']:.2f}" if c["mean_attempts"] is not None else DASH
        table.rows.append([task, method, variant, condition, f"{c['successes']}/{c['trials']}", c["rate"], attempts,
                           share, source, *[_errors_text(c, i) for i in range(1, depth + 1)], str(c["errors"])])
    return table


def system_tables(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[TextTable]:
    """The `contact` system's own tables: Table I."""
    return [table_i(records, cfg)]
