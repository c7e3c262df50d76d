"""A tiny fake task for campaign tests: a seeded coin instead of physics, on the Task API.

Imported as a plugin (`plugins=["tests.fake_tasks"]`) so spawned workers register it too. It
registers the task `fake-coin` and its two methods (tagged `fake-coin`, so they drive nothing else):
- "plain": one flip, no recovery.
- "recover": re-flips each skill a drawn number of times (extra executions, recovery transitions,
  two fake reasoning calls per recovery), then one more chance at success.

Variants:
- "fair" / "biased": success with p = 0.5 / 0.8 (+0.1 in condition "easy"), drawn from default_rng(seed).
- "raises": every trial with an even seed raises while its episode is built.
- "slow": like "fair" but sleeps 50 ms (for kill-and-resume tests).
- "hangs": the trial with seed 1 sleeps 60 s (for trial-timeout tests); the others take 0.3 s.
- "crashes": the trial with seed 1 kills its worker with os._exit(1) (only in a
  child process; in the main process it raises instead, so a test never kills pytest).
The robot misreads the coin on seeds divisible by 5, so the method's verdict (`framework_success`)
differs from the ground truth there.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.core.log import TrialLog
from kintsugi.core.record import ReasonerSettings
from kintsugi.core.registry import METHODS, TASKS
from kintsugi.core.task import Episode, Task
from kintsugi.methods.recovery.skill_log import PegFigures

P_SUCCESS = {"fair": 0.5, "biased": 0.8, "raises": 0.5, "crashes": 0.5, "slow": 0.5, "hangs": 0.5}
SKILLS = ("fit", "align", "insert")
METHOD_TAG = "fake-coin"


class CoinConfig(StrictModel):
    barrier_dir: str | None = None
    """With a directory, seeds 0 and 1 of "crashes" wait for each other before seed 1 crashes."""


def _maybe_crash(seed: int, barrier: str | None) -> None:
    """Seed 1 kills its worker. With a barrier directory, seeds 0 and 1 first wait for each other (and
    seed 0 then lingers), so the crash certainly hits a pool with both trials running."""
    if barrier and seed in (0, 1):
        Path(barrier, f"seed{seed}").touch()
        other = Path(barrier, f"seed{1 - seed}")
        deadline = time.monotonic() + 10
        while not other.exists() and time.monotonic() < deadline:
            time.sleep(0.005)
        lingered = Path(barrier, "seed0-lingered")
        if seed == 0 and not lingered.exists():  # only the first time, not when rerun alone
            lingered.touch()
            time.sleep(0.3)
    if seed != 1:
        return
    if multiprocessing.parent_process() is not None:
        os._exit(1)
    raise RuntimeError("would crash the worker (refusing to kill the main process)")


class CoinRobot:
    """Flips the episode's coin; what it reports is wrong on seeds divisible by 5."""

    def __init__(self, rng: np.random.Generator, p: float, misread: bool) -> None:
        self.rng, self.p, self.misread = rng, p, misread
        self.landed = False

    def flip(self, p: float | None = None) -> bool:
        self.landed = self.landed or bool(self.rng.random() < (self.p if p is None else p))
        return self.landed != self.misread

    def draw(self, n: int) -> int:
        return int(self.rng.integers(0, n))


class CoinEpisode(Episode):
    def __init__(self, variant: str, condition: str, seed: int) -> None:
        self._p = P_SUCCESS[variant] + (0.1 if condition == "easy" else 0.0)
        self._rng = np.random.default_rng(seed)
        self.robot = CoinRobot(self._rng, self._p, misread=seed % 5 == 0)
        self._sim_time = float(self._rng.uniform(1, 5))
        self._steps = int(self._rng.integers(100, 1000))

    def context(self, tags: frozenset[str], reasoner: ReasonerSettings, seed: int) -> None:
        return None

    def score(self) -> tuple[bool, None]:
        return self.robot.landed, None

    @property
    def params(self) -> dict[str, Any]:
        return {"p": self._p}

    @property
    def sim_time(self) -> float:
        return self._sim_time

    @property
    def physics_steps(self) -> int:
        return self._steps

    def close(self) -> None:
        pass


class FakeCoinTask(Task):
    name = "fake-coin"
    description = "seeded coin flips for campaign tests"
    config_type = CoinConfig
    method_tag = METHOD_TAG
    system = "peg"
    conditions = {"easy": "p + 0.1", "hard": "p as drawn"}
    default_conditions = ("easy", "hard")
    default_variants = tuple(P_SUCCESS)
    variants_help = ", ".join(P_SUCCESS)
    reference_method = "plain"

    def episode(self, cfg: CoinConfig, variant: str, condition: str, seed: int, video: bool = False) -> CoinEpisode:
        if variant == "raises" and seed % 2 == 0:
            raise RuntimeError(f"fake failure on seed {seed}")
        if variant == "crashes":
            _maybe_crash(seed, cfg.barrier_dir)
        if variant == "slow":
            time.sleep(0.05)
        if variant == "hangs":
            time.sleep(60.0 if seed == 1 else 0.3)
        return CoinEpisode(variant, condition, seed)


class Plain:
    def run(self, robot: CoinRobot, log: TrialLog) -> bool:
        return robot.flip()


class Recover:
    def run(self, robot: CoinRobot, log: TrialLog) -> bool:
        verdict = robot.flip()
        extra = {s: robot.draw(3) for s in SKILLS}
        for s in SKILLS:
            for _ in range(extra[s]):
                log.transition(s, SKILLS[robot.draw(3)])
                log.transcript += [{"role": "analyze", "latency_s": 0.01}, {"role": "plan", "latency_s": 0.01}]
        log.figures(PegFigures(extra_executions=extra))
        return robot.flip(0.5) or verdict


TASKS.register(FakeCoinTask.name, FakeCoinTask.description, tags=("test",))(FakeCoinTask)
METHODS.register("plain", "fake coin: one flip", tags=(METHOD_TAG,))(lambda ctx, settings: Plain())
METHODS.register("recover", "fake coin: re-flips with recovery transitions", tags=(METHOD_TAG,))(
    lambda ctx, settings: Recover())
