"""A PNG of the planner over a trial: lowest rollout cost, MPPI temperature and effective sample size.

Written beside a trial's video (`kintsugi run <contact task> --video out.mp4` -> out.plan.png), or from
any `PlanTrace` with `plot_plan`. Stage changes are drawn as vertical lines with the stage's name: a
cost that stays high after a transition, or an ESS pinned at its floor, is visible at a glance.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class PlanSeries:
    """Per planning step: sim time, stage, lowest cost, temperature, ESS as a fraction of the valid samples."""

    t: list[float] = field(default_factory=list)
    stage: list[str] = field(default_factory=list)
    cost: list[float] = field(default_factory=list)
    temperature: list[float] = field(default_factory=list)
    ess_frac: list[float] = field(default_factory=list)

    def add(self, t: float, stage: str, cost: float, temperature: float, ess_frac: float) -> None:
        self.t.append(float(t))
        self.stage.append(stage)
        self.cost.append(float(cost))
        self.temperature.append(float(temperature))
        self.ess_frac.append(float(ess_frac))


def plot_plan(series: PlanSeries, path: str | Path, title: str = "") -> Path:
    """Three stacked panels over sim time; returns the PNG's path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    t = np.asarray(series.t)
    fig, axes = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
    panels = ((series.cost, "lowest rollout cost", True), (series.temperature, "temperature λ", True),
              (series.ess_frac, "ESS / samples", False))
    for ax, (values, label, log) in zip(axes, panels):
        v = np.asarray(values, dtype=float)
        ok = np.isfinite(v) & ((v > 0) if log else True)
        ax.plot(t[ok], v[ok], lw=1.2)
        if log and ok.any():
            ax.set_yscale("log")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        for i in range(len(t)):
            if i == 0 or series.stage[i] != series.stage[i - 1]:
                ax.axvline(t[i], color="0.5", lw=0.8, ls="--")
                if ax is axes[0]:
                    ax.annotate(series.stage[i], (t[i], 1.0), xycoords=("data", "axes fraction"), rotation=90,
                                va="top", ha="right", fontsize=7, color="0.3")
    axes[-1].set_xlabel("sim time (s)")
    axes[-1].set_ylim(0, 1.05)
    if title:
        axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_path_for(video: str | Path) -> Path:
    """Where the plan plot of a video goes: beside it, `<stem>.plan.png`."""
    v = Path(video)
    return v.with_name(v.stem + ".plan.png")
