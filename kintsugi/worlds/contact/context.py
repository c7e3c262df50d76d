"""What a contact method is given besides the robot.

Task knowledge only: the config with every randomized range of the task's own sections
withheld (`withheld`: a size, mass, friction or start-pose range is None), the task's name,
instruction and target, and
the objects' known shapes (their 3D models) with fixtures and markers. No trial seed, no
world builder, no catalogue midpoints: each of them would let a method re-draw or centre on
the truth. The trial's true physics and seed reach only methods registered with the
`oracle-physics` tag (the expert baselines, whose planning world equals the truth BY DESIGN,
the paper's upper bound); everyone else gets None for both.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import get_args

from pydantic import BaseModel

from kintsugi.core.config import Range
from kintsugi.core.record import ReasonerSettings
from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.worlds.contact.objects import Physics
from kintsugi.worlds.contact.world import Scene

ORACLE_TAG = "oracle-physics"
METHOD_TAG = "system-c"


@dataclass(frozen=True)
class TaskBrief:
    """What a user tells the robot about a task: its name, the instruction and the object it is about."""

    name: str
    instruction: str
    target: str
    """The object the task is about (system identification fits its mass and friction)."""


def _is_range(annotation: object, metadata: list) -> bool:
    if any(m in Range.__metadata__ for m in metadata):
        return True
    return any(a is Range or _is_range(a, []) for a in get_args(annotation))


def withheld(cfg: ContactConfig) -> ContactConfig:
    """The config a non-oracle method sees: the sections every contact task shares (robot, table, simulation,
    control, method settings) as they are; in the task's own sections (its objects, fixtures, scoring) every
    randomized range (sizes, masses, frictions, start poses) is None. The middle of a mass range is a prior
    centred on the truth; the fixed task facts (a wall's place, a force target, a goal region) stay."""
    update = {}
    for name in type(cfg).model_fields:
        section = getattr(cfg, name)
        if name in ContactConfig.model_fields or not isinstance(section, BaseModel):
            continue
        ranges = {k: None for k, f in type(section).model_fields.items() if _is_range(f.annotation, f.metadata)}
        if ranges:
            update[name] = section.model_copy(update=ranges)
    return cfg.model_copy(update=update)


@dataclass
class ContactContext:
    cfg: ContactConfig
    """The task's config; for a non-oracle method `withheld(config)` (no randomized range)."""
    task: TaskBrief
    known: Scene
    """Object shapes, fixtures and markers (known models); its start poses are the tracker's first reading."""
    oracle_physics: dict[str, Physics] | None = None
    """The TRUE masses and frictions: only for `oracle-physics` methods (expert, expert-fsm)."""
    reasoner: ReasonerSettings = field(default_factory=ReasonerSettings)
    seed: int | None = None
    """The trial's seed: only for `oracle-physics` methods (it seeds their planner's noise). Other methods seed
    their planner from what the robot first observes (`kintsugi.methods.mppi.execute.observation_seed`)."""

    @property
    def task_text(self) -> str:
        return self.task.instruction
