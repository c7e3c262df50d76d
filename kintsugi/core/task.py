"""The task API: what a task hands the one runner, so that no task builds a method or a record.

A task (one registry entry) knows its config, variants, conditions and reference method, and
builds an `Episode` per trial: the world with its truth, the robot a method drives, the
method-side context (what a method may know), the scorer, and optionally a video sink. The
runner (`kintsugi.core.runner`) is the only place that joins an episode to a method and turns
the result into a `TrialRecord`; tasks never import methods.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar, Protocol

from pydantic import BaseModel

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.core.record import ReasonerSettings


class VideoSink(Protocol):
    """A trial video: fed by the world's ticks, labelled by the method's status, closed by the runner."""

    frames: list

    def status(self, label: str, verdict: str | None = None) -> None: ...

    def finish(self, text: str, success: bool) -> None: ...

    def save(self, path: str) -> Any:
        """Write the video; companions (e.g. a plot beside it) may be listed in an optional `notes`
        attribute as (event kind, detail) pairs, which the runner adds to the record's events."""


class Episode(ABC):
    """One trial's world, as a task hands it to the runner.

    `robot` is all a method drives; `context(...)` is all it may know besides. Ground truth is read
    only by `score()`, after the method has run, and by `params` (recorded for analysis, never given
    to a method).
    """

    world: Any
    """The evaluation world: where the truth lives; only the episode and its scorer read it."""
    robot: Any
    video: VideoSink | None = None

    @abstractmethod
    def context(self, tags: frozenset[str], reasoner: ReasonerSettings, seed: int) -> Any:
        """The method-side context; `tags` are the method's registry tags (e.g. `oracle-physics`)."""

    @abstractmethod
    def score(self) -> tuple[bool, BaseModel | None]:
        """Ground-truth success and the task's typed figures (the record's `task_figures`)."""

    @property
    @abstractmethod
    def params(self) -> dict[str, Any]:
        """The trial's drawn parameters (and measured truth) for the record."""

    @property
    def sim_time(self) -> float:
        return self.robot.sim_time

    @property
    def physics_steps(self) -> int:
        """Physics steps the evaluation world took (the world counts them)."""
        return self.world.steps

    def disturbances(self) -> list[tuple[float, str]]:
        """(sim time, what) of every disturbance the world applied (drops, shifts, knocks)."""
        return []

    def outcome_text(self, success: bool, verdict: bool) -> str:
        """The last line of the video: the scored outcome beside the method's own verdict."""
        return (f"outcome: ground truth {'SUCCESS' if success else 'FAILURE'}, "
                f"method's verdict {'success' if verdict else 'failure'}")

    def close(self) -> None:
        """Free the world's renderers and buffers."""
        self.world.close()


class Task(ABC):
    """A registered task: its settings and how a trial's episode is built."""

    name: str
    description: str = ""
    config_type: ClassVar[type[BaseModel]]
    method_tag: ClassVar[str]
    """Methods carrying this registry tag drive this task's robot (checked before any trial)."""
    system: ClassVar[str]
    """Which of the systems' tables fit its campaigns: `peg`, `tabletop`, `contact` or a plugin's own."""
    conditions: dict[str, str]
    default_conditions: tuple[str, ...]
    default_variants: tuple[str, ...] = ("default",)
    variants_help: str = "default (one variant)"
    reference_method: ClassVar[str]
    """The method that proves the task (the contract test runs it)."""
    default_method: ClassVar[str | None] = None
    """What `kintsugi run <task>` runs without --method (default: the reference method)."""
    suites: dict = {}
    contract_overrides: ClassVar[dict[str, Any]] = {}
    """What the task contract runs with: a short budget of the real world."""

    def config(self, overrides: dict | list) -> BaseModel:
        return apply_overrides(self.config_type(), overrides)

    def check_variant(self, name: str, config: BaseModel | None = None) -> None:
        if name not in self.default_variants:
            raise ConfigError(f"unknown variant {name!r} for {self.name}; known: {', '.join(self.default_variants)}")

    @abstractmethod
    def episode(self, cfg: BaseModel, variant: str, condition: str, seed: int, video: bool = False) -> Episode:
        """Build one trial's world (truth drawn from `seed`), robot, scorer and optional video."""
