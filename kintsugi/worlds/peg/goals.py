"""Default goals, taught once in the default condition (round peg aligned, hole at y = 0).

The paper recorded them by keyboard teleoperation; ours were found the same way
in spirit, by trying goals in the nominal world only (see `bench/teach_goals.py`),
and are stored in `default_goals.json`. They never depend on a trial's truth.
"""

from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.worlds.peg.skills import AXES, SEQUENCE, SKILLS

DEFAULT_GOALS_FILE = Path(__file__).with_name("default_goals.json")


@lru_cache(maxsize=8)
def load_goals(path: str | None = None) -> dict[str, dict[str, float]]:
    """Per-skill goals on the skill's own axes, in mm / degrees."""
    file = Path(path) if path else DEFAULT_GOALS_FILE
    try:
        raw = json.loads(file.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ConfigError(f"cannot read goals file {file}: {exc}") from None
    goals: dict[str, dict[str, float]] = {}
    for skill in SEQUENCE:
        values = raw.get(skill) if isinstance(raw, dict) else None
        if not isinstance(values, dict):
            raise ConfigError(f"goals file {file} lacks skill {skill!r}")
        extra = set(values) - set(SKILLS[skill].axes)
        if extra:
            raise ConfigError(f"goals file {file}: skill {skill!r} has no axes {sorted(extra)}")
        goals[skill] = {k: float(v) for k, v in values.items()}
    return goals


def to_si(values: dict[str, float]) -> dict[str, float]:
    """mm / degrees on named axes -> metres / radians."""
    return {a: (np.radians(v) if a == "roll" else v / 1000.0) for a, v in values.items()}


def full_goals(goals: dict[str, dict[str, float]], start: np.ndarray) -> dict[str, np.ndarray]:
    """Each skill's full [y, z, roll] goal (SI), '—' axes carried from the previous skill."""
    out, g = {}, start.copy()
    for skill in SEQUENCE:
        for axis, v in to_si(goals[skill]).items():
            g[AXES.index(axis)] = v
        out[skill] = g.copy()
    return out
