"""Cost of one environment step beside the world's raw stepping at the control rate, without rendering, per family
(peg, tabletop, contact): `env.step(hold)` (the driver's apply + one control tick + the observation + the info + the
scorer every `score_every` steps) vs the driver's `tick()` alone (the world's own control period: physics, health
check and watchers, exactly what any method's control loop runs), measured in the same run.

Like with like: both start from `reset(seed=0)` and run the same number of control periods under the same held
command (so the physics is the same trajectory); each repeat runs the two in turn, the order alternating, and the
ratio is taken per repeat (adjacent in time, so the machine's other load hits both alike); the median of the
repeats is reported with their range. Times are the process's CPU time (`time.process_time`), so that the other
programs sharing the machine's cores do not count as either's cost. `--profile` adds the cProfile of `env.step` per family.

    .venv/bin/python bench/bench_gym.py [--steps 400] [--repeats 7] [--profile]
"""

from __future__ import annotations

import argparse
import cProfile
import os
import platform
import pstats
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym  # noqa: E402

import kintsugi.gym  # noqa: E402,F401

FAMILIES = {"peg": "kintsugi/PegInsertion-v0", "tabletop": "kintsugi/PourSingle-v0",
            "contact": "kintsugi/PushForce-v0"}


def _raw(env, steps: int) -> float:  # noqa: ANN001
    env.reset(seed=0)
    tick = env.driver.tick
    start = time.process_time()
    for _ in range(steps):
        tick()
    return time.process_time() - start


def _env(env, steps: int) -> float:  # noqa: ANN001
    env.reset(seed=0)
    hold, step = env.driver.command(), env.step
    start = time.process_time()
    for _ in range(steps):
        step(hold)
    return time.process_time() - start


def measure(env, steps: int, repeats: int) -> dict[str, float]:  # noqa: ANN001
    """Per-repeat (raw s, env s, ratio), the order of the pair alternating between repeats."""
    raws, envs, ratios = [], [], []
    _env(env, min(steps, 50))  # warm caches (renderer-free paths, first scorer call)
    for r in range(repeats):
        if r % 2 == 0:
            raw, stepped = _raw(env, steps), _env(env, steps)
        else:
            stepped, raw = _env(env, steps), _raw(env, steps)
        raws.append(raw / steps)
        envs.append(stepped / steps)
        ratios.append(stepped / raw)
    return {"raw_us": statistics.median(raws) * 1e6, "env_us": statistics.median(envs) * 1e6,
            "ratio": statistics.median(ratios), "lo": min(ratios), "hi": max(ratios)}


def profile(env, steps: int) -> None:  # noqa: ANN001
    env.reset(seed=0)
    hold = env.driver.command()
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(steps):
        env.step(hold)
    prof.disable()
    pstats.Stats(prof).sort_stats("tottime").print_stats(12)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"machine: {platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, load {load:.2f}; "
          f"python {platform.python_version()}; {args.steps} control steps x {args.repeats} repeats, no rendering")
    for family, eid in FAMILIES.items():
        env = gym.make(eid, images=False, max_seconds=1e6).unwrapped
        try:
            m = measure(env, args.steps, args.repeats)
            print(f"{family:9s} {eid:26s} {env.driver.control_hz:5.0f} Hz  raw {m['raw_us']:7.1f} us/step  "
                  f"env {m['env_us']:7.1f} us/step  ratio {m['ratio']:.2f} (repeats {m['lo']:.2f}-{m['hi']:.2f})")
            if args.profile:
                profile(env, args.steps)
        finally:
            env.close()


if __name__ == "__main__":
    main()
