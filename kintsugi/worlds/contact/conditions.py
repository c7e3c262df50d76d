"""Randomized trial conditions: seed + condition -> one trial's hidden truth.

Every value is drawn in a fixed order whatever the condition, and a condition only
decides which draws are used (the rest take their range's midpoint). So trial i of
`pose`, `physics` and `random` share their draws, and methods meet identical trials.
"""

from __future__ import annotations

import numpy as np

from kintsugi.core.config import Range
from kintsugi.core.errors import ConfigError

CONDITIONS: dict[str, str] = {
    "none": "nominal world: every pose, size, mass and friction at the middle of its range",
    "pose": "start poses drawn from their ranges; sizes, masses and frictions nominal",
    "physics": "sizes, masses and frictions drawn from their ranges; start poses nominal",
    "random": "every start pose, size, mass and friction drawn from its range (the paper's randomization)",
    "all": "the same draws as `random` (the condition name every kintsugi task shares)",
}
_POSE = ("pose", "random", "all")
_PHYSICS = ("physics", "random", "all")


class Drawer:
    """Draws values for one trial and records them (flat `group.key` names) for the trial record."""

    def __init__(self, condition: str, seed: int) -> None:
        if condition not in CONDITIONS:
            raise ConfigError(f"unknown condition {condition!r}; known: {', '.join(CONDITIONS)}")
        self._rng = np.random.default_rng(seed)
        self._pose = condition in _POSE
        self._physics = condition in _PHYSICS
        self.drawn: dict[str, float] = {}

    def _draw(self, key: str, r: Range, use: bool) -> float:
        value = float(self._rng.uniform(r[0], r[1]))  # always drawn: keeps the stream paired
        out = value if use else (r[0] + r[1]) / 2
        self.drawn[key] = round(out, 6)
        return out

    def pose(self, key: str, r: Range) -> float:
        return self._draw(key, r, self._pose)

    def physics(self, key: str, r: Range) -> float:
        """Sizes, masses and frictions."""
        return self._draw(key, r, self._physics)

    def uniform(self, r: Range) -> float:
        """An unrecorded draw used under every condition but `none` (e.g. an angle around a ring)."""
        value = float(self._rng.uniform(r[0], r[1]))
        return value if (self._pose or self._physics) else (r[0] + r[1]) / 2


def mid(r: Range) -> float:
    return (r[0] + r[1]) / 2
