"""Cost of one environment step beside the world's raw stepping at the control rate, without rendering, per family
(peg, tabletop, contact): `env.step(hold)` (the driver's apply + one control tick + the observation + the info + the
scorer every `score_every` steps) vs the driver's `tick()` alone (the world's own control period: physics, health
check and watchers, exactly what any method's control loop runs), measured in the same run.

Like with like: two copies of the same trial (`reset(seed=0)`) run the same number of control periods under the same
held command (so the physics is the same trajectory), one by raw ticks and one by `env.step`, in alternating chunks
(`--chunk` periods, the order within a pair alternating too), so that the machine's other load falls on both alike;
the ratio is taken per repeat and the median of the repeats is reported with their range. Times are the process's CPU time (`time.process_time`), so that the other
programs sharing the machine's cores do not count as either's cost. `--profile` adds the cProfile of `env.step` per family.

    .venv/bin/python bench/bench_gym.py [--steps 400] [--repeats 7] [--profile] [--no-page]

Writes its table into docs/datasets.md (block `bench_gym`) unless `--no-page`.
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

from bench.pages import Block, command_line, write_block  # noqa: E402

import kintsugi.gym  # noqa: E402,F401

FAMILIES = {"peg": "kintsugi/PegInsertion-v0", "tabletop": "kintsugi/PourSingle-v0",
            "contact": "kintsugi/PushForce-v0"}


def run_pair(raw_env, step_env, steps: int, chunk: int, flip: bool) -> tuple[float, float]:  # noqa: ANN001
    """CPU seconds of `steps` raw ticks (on `raw_env`) and `steps` env steps (on `step_env`, the same trial), run
    in alternating chunks of `chunk` control periods so that the machine's load falls on both alike."""
    raw_env.reset(seed=0)
    step_env.reset(seed=0)
    tick, step, hold = raw_env.driver.tick, step_env.step, step_env.driver.command()
    clock = time.process_time
    raw = env = 0.0
    for i in range(steps // chunk):
        for part in ((0, 1) if (i % 2 == 0) != flip else (1, 0)):
            start = clock()
            if part == 0:
                for _ in range(chunk):
                    tick()
                raw += clock() - start
            else:
                for _ in range(chunk):
                    step(hold)
                env += clock() - start
    return raw, env


def measure(eid: str, steps: int, repeats: int, chunk: int) -> dict[str, float]:
    """Per repeat (raw s, env s, ratio); the median over repeats and the ratios' range."""
    raw_env = gym.make(eid, images=False, max_seconds=1e6).unwrapped
    step_env = gym.make(eid, images=False, max_seconds=1e6).unwrapped
    try:
        run_pair(raw_env, step_env, min(steps, 2 * chunk), chunk, False)  # warm up (first scorer call, caches)
        raws, envs, ratios = [], [], []
        for r in range(repeats):
            raw, env = run_pair(raw_env, step_env, steps, chunk, r % 2 == 1)
            raws.append(raw / steps)
            envs.append(env / steps)
            ratios.append(env / raw)
        return {"raw_us": statistics.median(raws) * 1e6, "env_us": statistics.median(envs) * 1e6,
                "ratio": statistics.median(ratios), "lo": min(ratios), "hi": max(ratios),
                "hz": step_env.driver.control_hz, "score_s": step_env.score_every_s}
    finally:
        raw_env.close()
        step_env.close()


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
    ap.add_argument("--chunk", type=int, default=20, help="control periods per alternating chunk")
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--no-page", action="store_true", help="print only; do not write docs/datasets.md")
    args = ap.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"machine: {platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, load {load:.2f}; "
          f"python {platform.python_version()}; {args.steps} control steps x {args.repeats} repeats in chunks of "
          f"{args.chunk}, no rendering")
    lines = ["| family | environment | control rate | raw tick (us) | env.step (us) | ratio (median, range) |",
             "|---|---|---|---|---|---|"]
    for family, eid in FAMILIES.items():
        m = measure(eid, args.steps, args.repeats, args.chunk)
        print(f"{family:9s} {eid:26s} {m['hz']:4.0f} Hz, scored every {m['score_s']:g} s  raw {m['raw_us']:7.1f} "
              f"us/step  env {m['env_us']:7.1f} us/step  ratio {m['ratio']:.2f} (repeats {m['lo']:.2f}-{m['hi']:.2f})")
        lines.append(f"| {family} | `{eid}` | {m['hz']:.0f} Hz | {m['raw_us']:.1f} | {m['env_us']:.1f} | "
                     f"{m['ratio']:.2f} ({m['lo']:.2f}-{m['hi']:.2f}) |")
        if args.profile:
            env = gym.make(eid, images=False, max_seconds=1e6).unwrapped
            profile(env, args.steps)
            env.close()
    lines += ["", f"CPU time per control period, {args.steps} periods x {args.repeats} repeats in alternating chunks of "
              f"{args.chunk}, no images, the scorer every {m['score_s']:g} s of sim time (the default); load average "
              f"{load:.1f} when it ran (other programs shared the {os.cpu_count()} cores)."]
    if not args.no_page:
        write_block(Path(__file__).resolve().parents[1] / "docs" / "datasets.md", Block("bench_gym", command_line(), lines))


if __name__ == "__main__":
    main()
