"""Cost of one environment step beside the world's raw stepping at the control rate, without rendering, for one
task per system: `env.step(hold)` (driver apply + tick + observation + the scorer every score_every steps) vs
the world's own control tick alone, measured in the same run.

    .venv/bin/python bench/bench_gym.py [--steps 500]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym  # noqa: E402

import kintsugi.gym  # noqa: E402,F401


def _raw(env, steps: int) -> float:  # noqa: ANN001
    env.reset(seed=0)
    d = env.driver
    start = time.perf_counter()
    for _ in range(steps):
        d.tick()
    return time.perf_counter() - start


def _env(env, steps: int) -> float:  # noqa: ANN001
    env.reset(seed=0)
    hold = env.driver.command()
    start = time.perf_counter()
    for _ in range(steps):
        env.step(hold)
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=500)
    args = ap.parse_args()
    for eid in ("kintsugi/PegInsertion-v0", "kintsugi/PourSingle-v0", "kintsugi/PushForce-v0"):
        env = gym.make(eid, images=False, max_seconds=1e6).unwrapped
        raw = min(_raw(env, args.steps) for _ in range(3))
        stepped = min(_env(env, args.steps) for _ in range(3))
        env.close()
        print(f"{eid:28s} raw {raw / args.steps * 1e6:8.1f} us/step  env {stepped / args.steps * 1e6:8.1f} us/step  "
              f"ratio {stepped / raw:.2f}")


if __name__ == "__main__":
    main()
