"""The step-level API: one control period at a time, over the same robot a method drives.

A `Driver` wraps one family's robot (peg, tabletop, contact) and offers what a policy needs at
the control rate: `observe()` (the robot's own sensors and cameras as named arrays), `apply(action)`
(the low-level command, clipped to its documented bounds), `tick()` (one control period of the world's
own stepping, with its watchers: scorers and disturbances run exactly as under any method), and
`command()` (the command in force, what a recorder logs). It reads the robot's sensors and writes its
actuators; it never reads ground truth.

`Feature` describes one observation entry (shape, bounds, dtype, unit) so that a Gymnasium space, a
LeRobot feature list and a robomimic key set are all built from one description.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from kintsugi.core.errors import KintsugiError

INF = math.inf
F64 = np.dtype(np.float64)
ND = np.ndarray


def clamp(vals: list[float], lo: list[float], hi: list[float]) -> list[float]:
    """Each value clipped to its bounds, as a new list (the lists have one length)."""
    return [a if v < a else b if v > b else v for v, a, b in zip(vals, lo, hi)]


def scatter(dst: Any, vals: list[float], pairs: tuple[tuple[int, int], ...]) -> None:
    """`dst[k] = vals[i]` for every `(i, k)` of `pairs`: what a driver writes to the actuators' targets."""
    for i, k in pairs:
        dst[k] = vals[i]


class DriverError(KintsugiError):
    """The robot cannot be driven step by step (an unknown family, a bad action)."""


@dataclass(frozen=True)
class Feature:
    shape: tuple[int, ...]
    low: float
    high: float
    dtype: str
    unit: str
    names: tuple[str, ...] | None = None
    image: bool = False


class Driver(ABC):
    family: str
    action_names: tuple[str, ...]
    action_unit: str
    control_hz: float

    def __init__(self) -> None:
        self.steps = 0
        """Control periods this driver ran."""
        self._last_quat: dict[str, list[float]] = {}

    # --- the action ---------------------------------------------------------------------------
    @property
    @abstractmethod
    def action_low(self) -> np.ndarray: ...

    @property
    @abstractmethod
    def action_high(self) -> np.ndarray: ...

    def clip(self, action: Any) -> np.ndarray:
        return np.array(self.clip_values(action))

    def clip_values(self, action: Any) -> list[float]:
        """The action clipped to the bounds, as floats (plain Python: this runs every control period, and numpy
        calls on a handful of values cost more than the physics of a light world). A float64 array of finite
        values (the common case: its values are floats already, and a finite sum means every value is finite) is
        clipped in one pass; anything else (a list, another dtype, a wrong length or shape) takes `_clip_checked`,
        which names the fault."""
        lo, hi = self._bounds
        if not lo:
            lo, hi = self._bounds = (self.action_low.tolist(), self.action_high.tolist())
        if type(action) is ND and action.dtype is F64:
            vals = action.tolist()
            if len(vals) == len(lo) and type(vals[0]) is float and -INF < sum(vals) < INF:
                return clamp(vals, lo, hi)
        return self._clip_checked(action, self._bounds)

    def _clip_checked(self, action: Any, bounds: tuple[list[float], list[float]]) -> list[float]:
        """`clip_values` for any input: a sequence of numbers, or a `DriverError` saying what is wrong with it."""
        try:
            vals = action.ravel().tolist() if isinstance(action, np.ndarray) else [float(v) for v in action]
            if len(vals) != len(bounds[0]):
                raise DriverError(f"a {self.family} action has {len(self.action_names)} values "
                                  f"({', '.join(self.action_names)}), not {len(vals)}")
            out = [lo if v < lo else hi if v > hi else float(v) for v, lo, hi in zip(vals, *bounds)]
        except (TypeError, ValueError):  # not numbers (strings, complex, objects)
            raise DriverError(f"a {self.family} action is a sequence of {len(self.action_names)} numbers "
                              f"({', '.join(self.action_names)}), not {action!r}") from None
        if not -INF < sum(vals) < INF and not all(math.isfinite(v) for v in vals):  # the sum: one check, fast
            raise DriverError(f"a {self.family} action must be finite, got {vals}")
        return out

    _bounds: tuple[list[float], list[float]] = ([], [])

    @abstractmethod
    def apply(self, action: Any) -> None:
        """Send one command (clipped to the bounds); it stays in force until the next."""

    @abstractmethod
    def tick(self) -> None:
        """One control period of the world, watchers included."""

    @abstractmethod
    def command(self) -> np.ndarray:
        """The command in force, as an action vector (what `apply` would take to send it again)."""

    def advance(self, action: Any, images: bool = True) -> tuple[dict[str, np.ndarray] | None, str | None]:
        """One period of a policy's loop: `apply(action)`, `tick()`, `observe(images)`. A bad action raises
        (`DriverError`, before any physics); a failing tick (a diverged simulation) is returned, not raised:
        `(None, "<ErrorType>: <message>")`, else `(observation, None)`. A driver may override it to reuse what
        its `apply` just wrote (nothing runs between the three but the world's own tick)."""
        self.apply(action)
        try:
            self.tick()
        except KintsugiError as exc:
            return None, f"{type(exc).__name__}: {exc}"
        return self.observe(images), None

    # --- the observation ----------------------------------------------------------------------
    @abstractmethod
    def features(self, images: bool = True) -> dict[str, Feature]: ...

    @abstractmethod
    def observe(self, images: bool = True) -> dict[str, np.ndarray]: ...

    @abstractmethod
    def render(self) -> np.ndarray:
        """One RGB frame of the robot's camera(s), for a viewer or a video."""

    @abstractmethod
    def record_ticks(self, on_tick: Callable[[np.ndarray], None]) -> None:
        """Have `on_tick(command)` called before every control period the world runs, whoever commands it
        (a method's skills or actions): how a trial's low-level trajectory is logged for replay."""

    @property
    def physics_steps(self) -> int:
        """Physics steps the driven world (`self.world`, set by each driver) has taken."""
        return self.world.steps

    @property
    def sim_time(self) -> float:
        return float(self.world.data.time)

    def continuous(self, key: str, quat: np.ndarray, w_index: int) -> np.ndarray:
        """`quat` on the hemisphere of the last one seen under `key` (q and -q are one rotation; a sign flip
        between frames ruins normalisation statistics and regression targets). The first is given w >= 0
        (`w_index`: where the scalar part is, 3 for x, y, z, w and 0 for w, x, y, z)."""
        return np.array(self.continuous_values(key, np.asarray(quat, dtype=np.float64).tolist(), w_index))

    def continuous_values(self, key: str, q: list[float], w_index: int) -> list[float]:
        """`continuous` on plain floats (the observation's hot path)."""
        ref = self._last_quat.get(key)
        if (q[w_index] < 0) if ref is None else (q[0] * ref[0] + q[1] * ref[1] + q[2] * ref[2] + q[3] * ref[3] < 0):
            q = [-v for v in q]
        self._last_quat[key] = q
        return q
