"""System B's Table I (AgentChord against the baselines) from tabletop trial records.

Every figure but success, sim time and errors comes from the record's `RunFigures` (through
`metrics_of`, which adds the measured execution time); a method that writes none (e.g.
`scripted`) shows "—" in those columns.

Columns:
- Success: ground truth, % [Wilson 95% interval]; a trial with `error` counts as a failure.
- Steps: mean episode steps over all trials (a trial failed early counts with its few steps).
- Exec s: sim time + measured reasoning latency; Modelled s: sim time + calls x the stated
  per-call latency (`latency_model_s`), a model of a remote endpoint.
- Calls plan / run: mean reasoning calls for the initial plan / after it.
- Completed: mean steps / modelled s over the trials the method completed (succeeded), the
  paper's "steps executed to complete a task".
- Latency: the largest recovery latency in the cell (monitor firing -> first recovery command),
  in control steps.
- Paired: over the seeds both the method and AgentChord solved in the same variant, condition and
  drop probability, mean steps / exec s / modelled s, the method's first (the like-for-like cost,
  which a mean over all trials hides when one method finishes at length trials the other fails early),
  and the differences (method - AgentChord).
"""

from __future__ import annotations

from typing import Any, Sequence

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.stats import fmt, format_rate, mean
from kintsugi.campaign.tables import TextTable, group_by_cell, successes
from kintsugi.core.record import TrialRecord
from kintsugi.methods.agentchord.method import AgentChordMetrics, metrics_of

REFERENCE = "agentchord"
DASH = "—"


def drop_p(records: Sequence[TrialRecord]) -> str:
    """The drop probability the trials ran with (a drawn parameter of the tabletop world), or "—"."""
    values = sorted({str(r.params["drop_p"]) for r in records if "drop_p" in r.params})
    return ", ".join(values) or DASH


def by_drop_p(rs: Sequence[TrialRecord]) -> dict[str, list[TrialRecord]]:
    """A cell's trials per drop probability; a trial that recorded none (one that errored before its world
    was drawn) joins the cell's only probability, or stands apart under "—" when the cell has several."""
    groups: dict[str, list[TrialRecord]] = {}
    for r in rs:
        groups.setdefault(drop_p([r]), []).append(r)
    if DASH in groups and len(groups) == 2:
        loose = groups.pop(DASH)
        groups[next(iter(groups))].extend(loose)
    return groups


def _metrics(rs: Sequence[TrialRecord]) -> list[AgentChordMetrics]:
    return [m for r in rs if (m := metrics_of(r)) is not None]


def _solved(rs: Sequence[TrialRecord]) -> dict[int, AgentChordMetrics]:
    """Seed -> figures of the trials that succeeded without error and carry figures."""
    return {r.seed: m for r in rs if r.success and r.error is None and (m := metrics_of(r)) is not None}


def paired(rs: Sequence[TrialRecord], reference: Sequence[TrialRecord]) -> tuple[str, str]:
    """(`it vs agentchord (n)`, differences) of steps / exec s / modelled s over the seeds both solved."""
    ref = _solved(reference)
    mine = _solved(rs)
    seeds = sorted(set(mine) & set(ref))
    if not seeds:
        return DASH, DASH
    fields = (("episode_steps", 1), ("execution_time_s", 2), ("modelled_execution_time_s", 1))
    a = [mean(getattr(mine[s], f) for s in seeds) for f, _ in fields]
    b = [mean(getattr(ref[s], f) for s in seeds) for f, _ in fields]
    # A tenth of a step and a hundredth of a second: where a drop leaves nothing to skip, two methods
    # differ by less than the whole-step, tenth-second rounding of the other columns.
    both = " / ".join(f"{x:.{d}f} vs {y:.{d}f}" for x, y, (_, d) in zip(a, b, fields))
    diff = " / ".join(f"{x - y:+.{d}f}" for x, y, (_, d) in zip(a, b, fields))
    return f"{both} ({len(seeds)})", diff


def _mean_of(ms: Sequence[Any], attr: str, digits: int) -> str:
    return fmt(mean(getattr(m, attr) for m in ms), digits) if ms else DASH


def table_i(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> TextTable:
    """Per cell (method, variant, condition, drop probability): success, steps, times, calls, recoveries, paired."""
    table = TextTable(
        title="Table I — success, steps, execution time and reasoning calls per cell",
        columns=["Method", "Variant", "Condition", "p", "n", "Success % [95% CI]", "Steps", "Sim s", "Exec s",
                 "Modelled s", "Calls plan / run", "Completed steps / modelled s", "Recoveries",
                 "Latency steps", "Err", "Paired: steps / exec s / modelled s (n)", "Paired diff"],
        notes=["Steps: mean episode steps; Exec s: sim time + measured reasoning latency; Modelled s: sim time + "
               "calls x the stated per-call latency. Calls: mean reasoning calls for the plan / after it. "
               "Completed: over the trials the method succeeded. Latency: the largest recovery latency "
               "(monitor firing -> first recovery command), control steps.",
               f"Paired: over the seeds both the method and {REFERENCE} solved (same variant, condition, p), "
               f"the method's figure first; diff: method - {REFERENCE}. — : the method records no run figures "
               "or no such seeds."],
    )
    cells: dict[tuple[str, str, str, str], list[TrialRecord]] = {}
    for (method, variant, condition), rs in group_by_cell(records, cfg).items():
        for p, group in by_drop_p(rs).items():
            cells[(method, variant, condition, p)] = group
    for (method, variant, condition, p), rs in cells.items():
        n = len(rs)
        ms = _metrics(rs)
        done = [m for r in rs if r.success and r.error is None and (m := metrics_of(r)) is not None]
        latency = [x for m in ms for x in m.recovery_latency_steps]
        calls = (f"{_mean_of(ms, 'planning_reasoning_calls', 1)} / {_mean_of(ms, 'runtime_reasoning_calls', 1)}"
                 if ms else DASH)
        completed = (f"{_mean_of(done, 'episode_steps', 0)} / {_mean_of(done, 'modelled_execution_time_s', 1)}"
                     if done else DASH)
        if method == REFERENCE or not ms:
            both, diff = DASH, DASH
        else:
            both, diff = paired(rs, cells.get((REFERENCE, variant, condition, p), []))
        table.rows.append([
            method, variant, condition, p, str(n), format_rate(successes(rs), n),
            _mean_of(ms, "episode_steps", 0), fmt(mean(r.sim_time for r in rs), 1),
            _mean_of(ms, "execution_time_s", 1), _mean_of(ms, "modelled_execution_time_s", 1), calls, completed,
            str(sum(m.recoveries for m in ms)) if ms else DASH, str(max(latency)) if latency else DASH,
            str(sum(r.error is not None for r in rs)), both, diff,
        ])
    return table


def system_tables(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[TextTable]:
    """The `tabletop` system's own tables: Table I."""
    return [table_i(records, cfg)]
