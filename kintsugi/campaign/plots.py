"""Campaign figures as PNG bytes (matplotlib, Agg backend: no display needed in workers or CI)."""

from __future__ import annotations

import io
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from kintsugi.campaign.plan import CampaignConfig  # noqa: E402
from kintsugi.campaign.stats import mean, wilson_interval  # noqa: E402
from kintsugi.campaign.tables import group_by_cell, successes  # noqa: E402
from kintsugi.core.record import TrialRecord  # noqa: E402


def _order(values: list[str]) -> list[str]:
    return list(dict.fromkeys(values))


def _png(fig: plt.Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def _axes(n: int, title: str) -> tuple[plt.Figure, list[plt.Axes]]:
    fig, axes = plt.subplots(1, n, figsize=(max(4.5, 4.2 * n), 3.8), squeeze=False, sharey=True,
                             layout="constrained")
    fig.suptitle(title)
    return fig, list(axes[0])


def _legend(fig: plt.Figure, ax: plt.Axes) -> None:
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=max(1, len(labels)), fontsize="small")


def success_plot(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> bytes:
    """Ground-truth success per condition with Wilson 95% error bars; bars grouped by method, a panel per variant."""
    groups = group_by_cell(records, cfg)
    methods = _order([m for m, _, _ in groups])
    variants = _order([v for _, v, _ in groups])
    conditions = _order([c for _, _, c in groups])
    fig, axes = _axes(len(variants), "Ground-truth success per condition (95% Wilson interval)")
    width = 0.8 / max(1, len(methods))
    x = np.arange(len(conditions))
    for ax, variant in zip(axes, variants):
        for j, method in enumerate(methods):
            rates, lows, highs = [], [], []
            for cond in conditions:
                rs = groups.get((method, variant, cond), [])
                k = successes(rs)
                p = k / len(rs) if rs else np.nan
                lo, hi = wilson_interval(k, len(rs)) if rs else (np.nan, np.nan)
                rates.append(100 * p)
                lows.append(100 * (p - lo))
                highs.append(100 * (hi - p))
            ax.bar(x + (j - (len(methods) - 1) / 2) * width, rates, width, yerr=[lows, highs],
                   capsize=3, label=method)
        ax.set_title(variant)
        ax.set_xticks(x, conditions, rotation=20, ha="right")
        ax.set_ylim(0, 105)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("success (%)")
    _legend(fig, axes[0])
    return _png(fig)


def extra_executions_plot(records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> bytes | None:
    """Mean extra executions per contact formation (system A's `PegFigures`), a panel per variant, pooled
    over conditions. None when no trial recorded any extra execution (nothing to plot)."""
    from kintsugi.campaign.systems.peg import extra_executions, ordered_skills

    recs = [r for r in records if r.error is None]
    extras = {id(r): extra_executions(r) for r in recs}
    skills = ordered_skills(k for e in extras.values() for k in e)
    methods = _order([r.method for r in recs if any(v > 0 for v in extras[id(r)].values())])
    if not skills or not methods:
        return None
    variants = _order([v for _, v, _ in group_by_cell(recs, cfg)])
    fig, axes = _axes(len(variants), "Mean extra executions per contact formation (pooled over conditions)")
    width = 0.8 / len(methods)
    x = np.arange(len(skills))
    for ax, variant in zip(axes, variants):
        for j, method in enumerate(methods):
            rs = [r for r in recs if r.method == method and r.variant == variant]
            vals = [mean(extras[id(r)].get(s, 0) for r in rs) for s in skills]
            ax.bar(x + (j - (len(methods) - 1) / 2) * width, vals, width, label=method)
        ax.set_title(variant)
        ax.set_xticks(x, [s.capitalize() for s in skills])
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("extra executions / trial")
    _legend(fig, axes[0])
    return _png(fig)


def plots_for(system: str | None, records: Sequence[TrialRecord], cfg: CampaignConfig | None = None) -> list[bytes]:
    """The campaign's figures: ground-truth success for every system, extra executions for `peg`."""
    images = [success_plot(records, cfg) if records else None]
    if system == "peg":
        images.append(extra_executions_plot(records, cfg))
    return [png for png in images if png]
