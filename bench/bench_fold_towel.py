"""fold-towel (system B, task 6) speed on this machine: cloth physics steps/s and scripted episodes.

    .venv/bin/python bench/bench_fold_towel.py [--trials 3] [--steps 1500]

(a) Raw `mj_step` steps per wall-second on one core for the towel scene (two arms at home, the
    cloth resting on the table), for the task's cloth (9 x 9) and the contract test's (5 x 5).
(c) Perceived towel features (seg + depth of both views -> cloud -> corners), per view.
(b) `fold-towel` with the `scripted` method through `run_trial` (condition `pose`): wall time per
    episode, physics steps, steps/s within the episode (perception and IK included), success.
Success rates with a Wilson CI come from `kintsugi bench fold-towel` (see the final report).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco

from kintsugi.tasks import TASKS, load_all
from kintsugi.trial import TrialSpec, run_trial


def raw_steps_per_s(overrides: dict, steps: int) -> float:
    task = TASKS.get("fold-towel").factory()
    world, *_ = task.build(task.config(overrides), "none", 0)
    for _ in range(50):  # let the cloth settle on the table first
        world.tick()
    t0 = time.perf_counter()
    mujoco.mj_step(world.model, world.data, nstep=steps)
    dt = time.perf_counter() - t0
    world.close()
    return steps / dt


def features_ms_per_view(repeats: int = 20) -> float:
    from kintsugi.tasks.tabletop.robot import TabletopRobot
    from kintsugi.tasks.tabletop.scene import CAMERAS

    task = TASKS.get("fold-towel").factory()
    world, *_ = task.build(task.config({}), "pose", 0)
    robot = TabletopRobot(world)
    robot.features()  # renderer start-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        robot.features()
        times.append(time.perf_counter() - t0)
    world.close()
    return 1000 * statistics.median(times) / len(CAMERAS)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--steps", type=int, default=1500)
    args = ap.parse_args()
    load_all()
    load = os.getloadavg()
    print(f"machine: {platform.system()} {platform.machine()}, {os.cpu_count()} CPUs, "
          f"load average {load[0]:.1f} (other work shares the cores: figures are lower bounds)")
    for label, ov in (("9 x 9 (task)", {}), ("5 x 5 (contract test)", {"towel.count": 5, "towel.spacing_m": 0.05})):
        print(f"cloth scene {label}, raw mj_step at rest: {raw_steps_per_s(ov, args.steps):,.0f} steps/s")
    print(f"towel features from seg+depth (corners), per view: median {features_ms_per_view():.1f} ms")
    walls, sps, ok = [], [], 0
    for seed in range(args.trials):
        r = run_trial(TrialSpec(task="fold-towel", method="scripted", variant="default", condition="pose", seed=seed))
        walls.append(r.wall_time)
        sps.append(r.physics_steps / r.wall_time)
        ok += r.success
        print(f"  seed {seed}: {'success' if r.success else 'failure'}, {r.physics_steps} steps "
              f"({r.sim_time:.2f} s simulated), {r.wall_time:.1f} s wall, {sps[-1]:,.0f} steps/s")
    print(f"fold-towel scripted episode ({args.trials} trials, pose): median wall {statistics.median(walls):.1f} s, "
          f"median {statistics.median(sps):,.0f} steps/s, {ok}/{args.trials} folded")


if __name__ == "__main__":
    main()
