"""System C's CoRAL methods (seed 004): `coral`, `l2r` and the ablations, registered like the contact methods."""

from __future__ import annotations

from typing import Any

from kintsugi.core.registry import METHODS

TAGS = ("system-c",)


def _make(name: str) -> Any:
    def make(ctx: Any, settings: object = None) -> Any:
        from kintsugi.methods.expert.method import _check
        from kintsugi.methods.coral.method import VARIANTS, Coral

        _check(ctx, name)
        return Coral(ctx, VARIANTS[name])

    return make


for _name, _help in (
    ("coral", "system C: CoRAL - physics priors, retrieval memory (coral.memory_path), formulated staged cost code "
              "with contact regions, MPPI attempts with the adaptation outer loop (sysid + strategy refinement)"),
    ("l2r", "system C: Language-to-Rewards - formulated cost code once, no contact strategy (no contact regions, "
            "no grasp side or height: the planner finds where to touch), one attempt, no adaptation, no memory"),
    ("coral-no-memory", "system C: CoRAL without the retrieval memory"),
    ("coral-no-refinement", "system C: CoRAL without the outer loop (attempts repeat with the same beliefs and code)"),
    ("coral-no-contact", "system C: CoRAL without a contact strategy (no contact regions, no grasp side or height: "
                         "the planner finds where to touch)"),
):
    METHODS.register(_name, _help, tags=TAGS)(_make(_name))
