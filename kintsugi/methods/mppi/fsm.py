"""Staged costs: a finite-state machine of MPPI costs with transition conditions.

Each stage is built when it is entered, from the measured state at that moment (a lift
target is "10 cm above where the box is now"). Its `done` condition is evaluated on the
measured state (observations), never on the planning world's predictions. A single-stage
cost is simply a machine with one stage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from kintsugi.methods.mppi.costs import Attractor, View
from kintsugi.worlds.contact.robot import Feedback, Observation

CostFn = Callable[[View], np.ndarray]
Done = Callable[[Observation], bool]
Guard = Callable[[Observation], "str | None"]
"""A path constraint over the whole attempt: None while it holds, else why it broke (the attempt fails there)."""


@dataclass
class Stage:
    name: str
    cost: CostFn
    """(K,) cost of each rollout."""
    done: Done
    """Transition condition on the measured state."""
    grip: float | None = None
    """Pinned gripper opening command (m); None lets MPPI plan the gripper."""
    timeout_s: float = math.inf
    """A stage that has not finished by then fails the attempt."""
    hold_s: float = 0.0
    """`done` must hold this long without a break before the machine moves on; a stage with a hold has its
    condition watched at the robot's inner rate (`StageMachine.watch`), as a scorer watches an unbroken band."""
    feedback: Feedback | None = None
    """Eq. 5's reactive correction at the inner rate while this stage runs."""
    attractors: tuple[Attractor, ...] = ()
    """Contact regions this stage's cost attracts the TCP to (also drawn in videos)."""
    seed_plan: dict[int, float] = field(default_factory=dict)
    """Actuator index -> a command the plan restarts from when the stage begins (see MPPI.hold)."""
    noise_scale: float = 1.0
    """Multiplies MPPI's sampling noise while this stage runs (fine force regulation wants less)."""
    goal: dict[str, float] = field(default_factory=dict)
    """A few numbers describing the stage's target, for the trial record."""


StageFactory = Callable[[Observation], Stage]


@dataclass
class Transition:
    stage: str
    t_enter: float
    t_exit: float
    reached: bool
    goal: dict[str, float]
    ee: np.ndarray
    why: str = ""
    """Why a stage failed other than on its timeout (a broken path constraint)."""


class StageMachine:
    """Runs stage factories in order; `update` advances on measured transitions and timeouts. `guards` are
    checked on every observation, the inner rate's included: one that breaks fails the running stage and the
    attempt."""

    def __init__(self, factories: list[StageFactory], guards: tuple[Guard, ...] = ()) -> None:
        self._factories = factories
        self.guards = guards
        self.broken: str | None = None
        self.index = -1
        self.stage: Stage | None = None
        self.entered = 0.0
        self._held_since: float | None = None
        self.history: list[Transition] = []
        self.finished = False
        self.failed = False

    def update(self, obs: Observation) -> bool:
        """Check the current stage's condition on `obs`; returns True if the stage changed."""
        if self.finished:
            return False
        if self.stage is None:
            self._enter(0, obs)
            self._check(obs)
            return True
        if self._check(obs):
            return True
        changed = False
        while self.stage is not None and self._met(obs):
            self._leave(obs, reached=True)
            changed = True
            if self.index + 1 >= len(self._factories):
                self.stage, self.finished = None, True
                break
            self._enter(self.index + 1, obs)
        if self.stage is not None and obs.t - self.entered > self.stage.timeout_s:
            self._leave(obs, reached=False)
            self.stage, self.finished, self.failed = None, True, True
            changed = True
        return changed

    def close(self, obs: Observation) -> None:
        """The attempt ended (time budget): log the unfinished stage."""
        if self.stage is not None:
            self._leave(obs, reached=False)
            self.stage = None

    def watch(self, obs: Observation) -> None:
        """An inner-rate observation between two updates: the guards are checked on it, and a stage with a hold
        restarts its hold timer when its condition breaks at any tick, not only at the ticks the planner replans on."""
        if self.stage is None or self.finished or self._check(obs) or self.stage.hold_s <= 0:
            return
        if not self.stage.done(obs):
            self._held_since = None
        elif self._held_since is None:
            self._held_since = obs.t

    def _check(self, obs: Observation) -> bool:
        """Whether a guard broke on `obs` (the running stage then fails with the reason)."""
        for guard in self.guards:
            why = guard(obs)
            if why is not None:
                self.broken = why
                self._leave(obs, reached=False, why=why)
                self.stage, self.finished, self.failed = None, True, True
                return True
        return False

    @property
    def succeeded(self) -> bool:
        return self.finished and not self.failed

    def _met(self, obs: Observation) -> bool:
        assert self.stage is not None
        if not self.stage.done(obs):
            self._held_since = None
            return False
        if self._held_since is None:
            self._held_since = obs.t
        return obs.t - self._held_since >= self.stage.hold_s - 1e-9

    def _enter(self, index: int, obs: Observation) -> None:
        self.index = index
        self.stage = self._factories[index](obs)
        self.entered = obs.t
        self._held_since = None

    def _leave(self, obs: Observation, reached: bool, why: str = "") -> None:
        assert self.stage is not None
        self.history.append(Transition(stage=self.stage.name, t_enter=self.entered, t_exit=obs.t, reached=reached,
                                       goal=dict(self.stage.goal), ee=obs.ee.copy(), why=why))
