"""The recovery method's settings (`--set method.<key>=...`, or `methods.recovery.<key>` in a campaign)."""

from __future__ import annotations

from pydantic import Field, field_validator

from kintsugi.core.config import Range, StrictModel
from kintsugi.worlds.peg.config import RECOVERY_SKILL_NAMES


class RecoverySettings(StrictModel):
    """`--set method.<key>=...` for the recovery method: its timeout, its clamp and what a plan may use."""

    max_consecutive_failures: int = Field(10, ge=1)
    """The paper's timeout: this many failed executions in a row end the trial as a failure."""
    max_executions: int = Field(40, ge=3)
    """Hard cap on skill executions in one trial, whatever the verdicts."""
    max_step_mm: float = Field(10.0, gt=0)
    """Largest change of one goal per recovery (the paper's real-robot failure was an over-large update)."""
    workspace_y_mm: Range = (-120.0, 120.0)
    workspace_z_mm: Range = (100.0, 200.0)
    skills: tuple[str, ...] = ("fit", "align", "insert")
    """Skills a recovery plan may use. The paper's are CF2..CF4; adding `approach` and `contact`
    lets a plan back out of the hole and re-approach (with a corrected roll)."""

    @field_validator("skills")
    @classmethod
    def _known_skills(cls, v: tuple[str, ...]) -> tuple[str, ...]:
        unknown = [s for s in v if s not in RECOVERY_SKILL_NAMES]
        if unknown:
            raise ValueError(f"unknown recovery skill {unknown[0]!r}; allowed: {', '.join(RECOVERY_SKILL_NAMES)}")
        if not v:
            raise ValueError(f"needs at least one skill of {', '.join(RECOVERY_SKILL_NAMES)}")
        dupes = sorted({s for s in v if v.count(s) > 1})
        if dupes:
            raise ValueError(f"lists {', '.join(dupes)} more than once")
        return tuple(s for s in RECOVERY_SKILL_NAMES if s in v)  # contact-formation order
