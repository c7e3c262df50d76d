"""A named campaign of one task (`kintsugi bench <task> --suite <name>`): its cells and config, fixed by name.

Tasks offer theirs through a `suites` mapping; `campaign.plan.suite_of` looks one up. A user's
options given on the command line go on top of the suite's.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field

from kintsugi.core.config import StrictModel


class Suite(StrictModel):
    name: str
    description: str
    methods: tuple[str, ...]
    shapes: tuple[str, ...]
    """Variants (the CLI's --shapes/--variants)."""
    conditions: tuple[str, ...]
    trials: int = Field(ge=1)
    overrides: dict[str, Any]
    """Dotted config overrides of the task, as `--set` takes them."""
    companion: str | None = None
    """The suite to run beside this one for comparison (same world, other options)."""
