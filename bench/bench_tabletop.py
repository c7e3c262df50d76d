"""Tabletop (system B) speed on this machine: IK per target, physics steps/s, scripted pour episodes.

    .venv/bin/python bench/bench_tabletop.py [--trials 10] [--ik-targets 300]

(a) IK per target (mink + daqp on the kinematic arm model): side grasps, top-down grasps and
    pouring poses in the work area, solved cold from home and warm from a nearby solution.
(b) Physics steps per wall-second on one core for the full scene (two arms, all eight objects
    resting on the table, both arms moving): raw `mj_step`, and through the world's control tick.
(c) `pour-single` with the `scripted` method through `run_trial` (condition `pose`): wall time
    per episode (EGL start-up included) and ground-truth success.
(d) Object features from seg + depth renders, per camera view (render, cloud, primitive fit).
Targets: IK <= 2 ms, >= 15k steps/s, pour episode <= 2 s, features <= 15 ms per view.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import time

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np

from kintsugi.worlds.tabletop.config import OBJECT_KINDS, TabletopConfig
from kintsugi.worlds.tabletop.ik import ArmIK
from kintsugi.worlds.tabletop.perceive import ObjectPerception
from kintsugi.worlds.tabletop.planning import down_rotation, side_rotation
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

FULL_LAYOUT = {
    "bottle": StartPose(x=0.45, y=-0.35), "cup": StartPose(x=0.45, y=-0.15), "plate": StartPose(x=0.58, y=0.05),
    "fork": StartPose(x=0.28, y=0.15), "spoon": StartPose(x=0.28, y=-0.05), "block": StartPose(x=0.45, y=0.30),
    "capsule": StartPose(x=0.30, y=0.35), "tray": StartPose(x=0.62, y=-0.35),
}


def _ms(xs: list[float]) -> str:
    return f"median {1000 * statistics.median(xs):.2f} ms, p90 {1000 * float(np.percentile(xs, 90)):.2f} ms"


def bench_ik(n: int) -> dict[str, list[float]]:
    cfg = TabletopConfig()
    ik = ArmIK(cfg.robot, cfg.motion, "right")
    base = np.array([cfg.robot.base_x_m, -cfg.robot.base_spacing_m / 2])
    rng = np.random.default_rng(0)
    out: dict[str, list[float]] = {"cold": [], "warm": [], "failed": []}
    for i in range(n):
        p = np.array([rng.uniform(0.25, 0.6), rng.uniform(-0.45, 0.05), rng.uniform(0.04, 0.35)])
        yaw = math.atan2(p[1] - base[1], p[0] - base[0])
        rot = side_rotation(yaw) if i % 2 else down_rotation(yaw + rng.uniform(-1.2, 1.2))
        t = time.perf_counter()
        r = ik.solve(p, rot, ik.home)
        out["cold"].append(time.perf_counter() - t)
        if not r.ok:
            out["failed"].append(1.0)
            continue
        t = time.perf_counter()  # a 1 cm step from the solution: what a straight-line move does
        ik.solve(p + rng.normal(0, 0.006, 3), rot, r.q)
        out["warm"].append(time.perf_counter() - t)
    return out


def bench_steps(n: int, repeats: int = 3) -> tuple[float, float]:
    cfg = TabletopConfig()
    world = TabletopWorld(cfg, OBJECT_KINDS, FULL_LAYOUT)
    m, d = world.model, world.data
    home = world.joint_targets("left")
    raw, framework = [], []
    for _ in range(repeats):
        t = time.perf_counter()
        for k in range(n // 10):  # both arms swing while objects rest (their contacts stay active)
            s = 0.3 * math.sin(k * 0.02)
            for arm in ("left", "right"):
                world.set_joint_targets(arm, home + s)
            mujoco.mj_step(m, d, nstep=10)
        raw.append(n / (time.perf_counter() - t))
        t = time.perf_counter()
        ticks = n // world.steps_per_tick
        for k in range(ticks):
            s = 0.3 * math.sin(k * 0.1)
            for arm in ("left", "right"):
                world.set_joint_targets(arm, home + s)
            world.tick()
        framework.append(ticks * world.steps_per_tick / (time.perf_counter() - t))
    world.check_health()
    world.close()
    return max(raw), max(framework)


def bench_features(n: int) -> list[float]:
    world = TabletopWorld(TabletopConfig(), OBJECT_KINDS, FULL_LAYOUT)
    perception = ObjectPerception(world)
    perception.features()  # GL context start-up
    times = []
    for _ in range(n):
        t = time.perf_counter()
        perception.features()
        times.append((time.perf_counter() - t) / 2)  # two views per call
    world.close()
    return times


def bench_pour(n: int) -> tuple[list[float], int, list[int]]:
    walls, ok, steps = [], 0, []
    for seed in range(n):
        rec = run_trial(TrialSpec(task="pour-single", method="scripted", variant="default", condition="pose",
                                  seed=seed))
        if rec.error:
            raise SystemExit(f"trial {rec.key} failed: {rec.error}")
        walls.append(rec.wall_time)
        ok += rec.success
        steps.append(rec.physics_steps)
    return walls, ok, steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--ik-targets", type=int, default=300)
    ap.add_argument("--steps", type=int, default=20000)
    args = ap.parse_args()
    print(f"machine: {platform.system()} {platform.machine()}, {os.cpu_count()} CPUs, "
          f"Python {platform.python_version()}, mujoco {mujoco.__version__}")
    ik = bench_ik(args.ik_targets)
    print(f"IK per target, cold from home ({len(ik['cold'])} targets, {len(ik['failed'])} unreachable): "
          f"{_ms(ik['cold'])}   (target <= 2 ms)")
    print(f"IK per target, warm (1 cm step, {len(ik['warm'])}): {_ms(ik['warm'])}")
    raw, fw = bench_steps(args.steps)
    print(f"full scene (2 arms, 8 objects), one core: raw mj_step {raw:,.0f} steps/s, "
          f"world tick {fw:,.0f} steps/s   (target >= 15,000)")
    feats = bench_features(10)
    print(f"object features from seg+depth, per view: {_ms(feats)}   (target <= 15 ms)")
    walls, ok, steps = bench_pour(args.trials)
    print(f"pour-single scripted episode ({args.trials} trials, condition pose): wall {_ms(walls).replace(' ms', ' ms')}"
          f", {statistics.median(steps):,.0f} physics steps; {ok}/{args.trials} ground-truth successes"
          f"   (target <= 2 s)")


if __name__ == "__main__":
    main()
