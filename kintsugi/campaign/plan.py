"""A campaign's config and its expansion into trials.

Trial i of every (method, variant, condition) cell uses seed base_seed + i, so
every method meets the same randomized conditions: comparisons are paired.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import Field, field_validator

from kintsugi.config import StrictModel
from kintsugi.trial import ReasonerSettings, TrialSpec

# Fields that may change between runs into the same out dir: the trial count may
# grow (or shrink), and which trials record videos does not change any outcome.
RESUMABLE_FIELDS = frozenset({"trials", "videos_per_cell"})


class CampaignConfig(StrictModel):
    """Everything that defines a campaign's trials; unknown keys are rejected."""

    task: str
    methods: list[str] = Field(min_length=1)
    variants: list[str] = Field(min_length=1)
    conditions: list[str] = Field(min_length=1)
    trials: int = Field(default=30, ge=1, description="trials per (method, variant, condition) cell")
    base_seed: int = Field(default=0, ge=0)
    overrides: dict[str, Any] = Field(default_factory=dict)
    reasoner: ReasonerSettings = ReasonerSettings()
    plugins: list[str] = Field(
        default_factory=list,
        description="modules imported in every worker before running, so third-party tasks register",
    )
    videos_per_cell: int = Field(default=0, ge=0, description="record a video of the first N trials of each cell")

    @field_validator("task")
    @classmethod
    def _task_name(cls, v: str) -> str:
        _check_name(v, "task")
        return v

    @field_validator("methods", "variants", "conditions")
    @classmethod
    def _names(cls, v: list[str], info: Any) -> list[str]:
        for name in v:
            _check_name(name, info.field_name)
        dupes = sorted({n for n in v if v.count(n) > 1})
        if dupes:
            raise ValueError(f"{info.field_name} lists {', '.join(dupes)} more than once")
        return v

    def cells(self) -> list[tuple[str, str, str]]:
        """(method, variant, condition) in config order: methods outermost."""
        return [(m, v, c) for m in self.methods for v in self.variants for c in self.conditions]

    def seeds(self) -> list[int]:
        return [self.base_seed + i for i in range(self.trials)]


def _check_name(name: str, what: str) -> None:
    # Names go into trial keys "task/method/variant/condition/seed" and file names.
    if not name or "/" in name or name != name.strip():
        raise ValueError(f"{what} name {name!r} must be non-empty, without '/' or surrounding spaces")


def video_path(video_dir: Path, key: str) -> Path:
    """Where a trial's video goes: one file per key, '/' replaced so it is a flat file name."""
    return video_dir / (key.replace("/", "__") + ".mp4")


def expand(cfg: CampaignConfig, video_dir: Path | None = None) -> list[TrialSpec]:
    """All trials of the campaign, cell by cell in config order, seeds base_seed + i."""
    specs: list[TrialSpec] = []
    for method, variant, condition in cfg.cells():
        for i, seed in enumerate(cfg.seeds()):
            spec = TrialSpec(
                task=cfg.task,
                method=method,
                variant=variant,
                condition=condition,
                seed=seed,
                overrides=cfg.overrides,
                reasoner=cfg.reasoner,
            )
            if video_dir is not None and i < cfg.videos_per_cell:
                spec = spec.model_copy(update={"video": str(video_path(video_dir, spec.key))})
            specs.append(spec)
    return specs
