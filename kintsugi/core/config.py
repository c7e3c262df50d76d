"""Typed configs that reject unknown keys, and `--set a.b=value` overrides on top of them."""

from __future__ import annotations

import json
from typing import Any, Annotated, TypeVar

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, model_validator

from kintsugi.core.errors import ConfigError

M = TypeVar("M", bound=BaseModel)


class StrictModel(BaseModel):
    """Frozen pydantic model; an unknown key is an error, not a silent no-op."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class SimSection(StrictModel):
    """The physics settings every world has: its timestep and its contact stiffness (MuJoCo's solref
    time constant), which must span at least two steps of the finest world that simulates it or
    contacts ring and the simulation diverges. A world subclasses it with its own defaults and fields."""

    timestep_s: float = Field(0.002, gt=0, le=0.005)
    contact_timeconst_s: float = Field(0.004, gt=0)
    """Contact stiffness (solref); keep it >= 2 x the timestep."""

    def coarsest_step(self) -> tuple[str, float]:
        """(field, seconds) of the coarsest timestep stepping these contacts."""
        return "timestep_s", self.timestep_s

    @model_validator(mode="after")
    def _stable(self) -> "SimSection":
        name, dt = self.coarsest_step()
        if self.contact_timeconst_s < 2 * dt:
            raise ValueError(f"sim.contact_timeconst_s must be >= 2 x sim.{name}")
        return self


def _ordered(r: tuple[float, float]) -> tuple[float, float]:
    if r[0] > r[1]:
        raise ValueError(f"range [{r[0]}, {r[1]}] has low > high")
    return r


Range = Annotated[tuple[float, float], AfterValidator(_ordered)]
"""A closed interval [low, high] sampled uniformly; [x, x] means fixed."""


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split `a.b.c=value`; the value is JSON when it parses (numbers, lists), else a string."""
    if "=" not in text:
        raise ConfigError(f"override {text!r} must look like key.path=value")
    key, raw = text.split("=", 1)
    path = [p for p in key.strip().split(".") if p]
    if not path:
        raise ConfigError(f"override {text!r} has an empty key")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw.strip()
    return path, value


def apply_overrides(model: M, overrides: list[str] | dict[str, Any], prefix: str = "") -> M:
    """Return a copy of `model` with dotted overrides applied and validated.

    Unknown keys and bad values raise ConfigError naming the dotted key (under `prefix`, e.g.
    `method.`, when the model is one section of what a user sets).
    """
    pairs = (
        [parse_override(o) for o in overrides]
        if isinstance(overrides, list)
        else [(k.split("."), v) for k, v in overrides.items()]
    )
    data = model.model_dump(mode="python")
    for path, value in pairs:
        node: Any = data
        for i, part in enumerate(path):
            if not isinstance(node, dict) or part not in node:
                where = ".".join([prefix] * bool(prefix) + path[:i]) or "(top level)"
                known = (", ".join(sorted(node)) or "none") if isinstance(node, dict) else "(not a section)"
                dotted = ".".join([prefix] * bool(prefix) + path)
                raise ConfigError(f"unknown config key {dotted!r}: {where} has keys {known}")
            if i == len(path) - 1:
                node[part] = value
            else:
                node = node[part]
    try:
        return type(model).model_validate(data)
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join([prefix] * bool(prefix) + [str(p) for p in err['loc']])}: {err['msg']}" for err in exc.errors()
        )
        raise ConfigError(f"bad config value: {problems}") from None
