"""A tiny fake task for campaign tests: a seeded coin instead of physics.

Imported as a plugin (`plugins=["tests.fake_tasks"]`) so spawned workers register it too.

Variants:
- "fair" / "biased": success with p = 0.5 / 0.8, drawn from default_rng(seed).
- "raises": every trial with an even seed raises inside run().
- "wrong-key": returns a record with another trial's key (a buggy task).
- "slow": like "fair" but sleeps 50 ms (for kill-and-resume tests).
- "hangs": the trial with seed 1 sleeps 60 s (for trial-timeout tests); the others take 0.3 s.
- "crashes": the trial with seed 1 kills its worker with os._exit(1) (only in a
  child process; in the main process it raises instead, so a test never kills pytest).
Methods: "baseline" has no recovery; "recover" reports extra executions and transitions.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from pathlib import Path

import numpy as np

from kintsugi.core.registry import TASKS
from kintsugi.core.record import TrialRecord, TrialSpec

P_SUCCESS = {"fair": 0.5, "biased": 0.8, "raises": 0.5, "crashes": 0.5, "wrong-key": 0.5, "slow": 0.5,
             "hangs": 0.5}
SKILLS = ("fit", "align", "insert")


def _maybe_crash(spec: TrialSpec) -> None:
    """Seed 1 kills its worker. With overrides["barrier_dir"], seeds 0 and 1 first wait for each
    other (and seed 0 then lingers), so the crash certainly hits a pool with both trials running."""
    barrier = spec.overrides.get("barrier_dir")
    if barrier and spec.seed in (0, 1):
        Path(barrier, f"seed{spec.seed}").touch()
        other = Path(barrier, f"seed{1 - spec.seed}")
        deadline = time.monotonic() + 10
        while not other.exists() and time.monotonic() < deadline:
            time.sleep(0.005)
        lingered = Path(barrier, "seed0-lingered")
        if spec.seed == 0 and not lingered.exists():  # only the first time, not when rerun alone
            lingered.touch()
            time.sleep(0.3)
    if spec.seed != 1:
        return
    if multiprocessing.parent_process() is not None:
        os._exit(1)
    raise RuntimeError("would crash the worker (refusing to kill the main process)")


class FakeCoinTask:
    methods = ("baseline", "recover")  # its own methods, not the METHODS registry

    def run(self, spec: TrialSpec) -> TrialRecord:
        rng = np.random.default_rng(spec.seed)
        if spec.variant == "raises" and spec.seed % 2 == 0:
            raise RuntimeError(f"fake failure on seed {spec.seed}")
        if spec.variant == "crashes":
            _maybe_crash(spec)
        if spec.variant == "slow":
            time.sleep(0.05)
        if spec.variant == "hangs":
            time.sleep(60.0 if spec.seed == 1 else 0.3)
        p = P_SUCCESS[spec.variant] + (0.1 if spec.condition == "easy" else 0.0)
        success = bool(rng.random() < p)
        extra: dict[str, int] = {}
        transitions: list[tuple[str, str]] = []
        if spec.method == "recover":
            extra = {s: int(rng.integers(0, 3)) for s in SKILLS}
            for s in SKILLS:
                for _ in range(extra[s]):
                    transitions.append((s, SKILLS[int(rng.integers(0, 3))]))
            success = success or bool(rng.random() < 0.5)
        calls = len(transitions) * 2
        return TrialRecord(
            key=spec.key if spec.variant != "wrong-key" else "bogus", task=spec.task, method=spec.method, variant=spec.variant,
            condition=spec.condition, seed=spec.seed,
            params={"p": p},
            success=success,
            framework_success=success if spec.seed % 5 else not success,
            extra_executions=extra,
            transitions=transitions,
            sim_time=float(rng.uniform(1, 5)),
            physics_steps=int(rng.integers(100, 1000)),
            reasoning_calls=calls,
            reasoning_latency_s=0.01 * calls,
        )


@TASKS.register("fake-coin", "seeded coin flips for campaign tests", tags=("test",))
def make_fake_coin() -> FakeCoinTask:
    return FakeCoinTask()
