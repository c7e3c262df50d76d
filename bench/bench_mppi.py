"""MPPI planning rate on system C's contact world, and what the planning costs beyond its physics.

One MPPI iteration (sample knots, spline them, roll out K samples in the planning world, a
vectorized cost over the rollouts, ESS-bisection temperature, weighted update) is timed
against the raw rollout of the SAME controls from the same state (contacts cost what they
cost), re-run on its own right after, so load drift hits both alike. Medians are reported. The scene: pick-box with the hand beside the box
and the expert's reach cost (distance to a grasp point, yaw, smoothness).

Last line: one JSON object with hz, samples, horizon_s, overhead (iteration / raw rollout).
Usage: .venv/bin/python bench/bench_mppi.py [--samples 256] [--horizon 0.5] [--iters 40]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import kintsugi  # noqa: F401 - sets MUJOCO_GL
import mujoco
import numpy as np

from kintsugi.control import MPPI, MPPIConfig
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import PickBoxConfig
from kintsugi.methods.mppi.costs import View, norm, smoothness, total, yaw_error
from kintsugi.worlds.contact.pick_box import TASK
from kintsugi.worlds.contact.robot import ContactRobot
from kintsugi.worlds.contact.world import EvaluationWorld, PlanningWorld


def machine() -> str:
    cpu = platform.processor() or "?"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return f"{cpu}; {os.cpu_count()} logical cores; {platform.system()} {platform.release()}; mujoco {mujoco.__version__}"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--horizon", type=float, default=0.5)
    ap.add_argument("--iters", type=int, default=40)
    ap.add_argument("--nthread", type=int, default=None)
    args = ap.parse_args()
    print("machine:", machine())

    cfg = PickBoxConfig()
    setup = TASK.build(cfg, Drawer("none", 0))
    world = EvaluationWorld(cfg, setup.scene, setup.truth)
    planning = PlanningWorld(cfg, setup.scene, setup.truth)
    robot = ContactRobot(world)
    box = robot.observe().objects["box"].pos
    obs = robot.act(np.array([box[0] - 0.06, box[1], 0.02, 0.0, 0.08]), 1.0)  # beside the box, low

    def cost(batch) -> np.ndarray:  # noqa: ANN001
        v = View(batch, planning.layout, obs)
        goal = v.pos("box").copy()
        goal[..., 2] = 0.01
        return total(10 * norm(v.tcp - goal) + yaw_error(v.yaw, 0.0) ** 2 + 50 * smoothness(v))

    mcfg = MPPIConfig(samples=args.samples, horizon_s=args.horizon, knots=4, noise_frac=0.04, nthread=args.nthread)
    mppi = MPPI(planning.model, mcfg, cost)
    data = planning.sync(obs.ee, obs.ee_vel, obs.fingers, obs.finger_vel,
                         {k: (o.pos, o.quat, o.lin_vel, o.ang_vel) for k, o in obs.objects.items()}, obs.ctrl, obs.t)
    for _ in range(3):  # warm up threads and caches
        mppi.step(data)
    iters, raws, inside = [], [], []
    for _ in range(args.iters):
        mppi.step(data)
        iters.append(mppi.last.total_s)
        inside.append(mppi.last.rollout_s)
        controls = mppi.last_batch.controls
        t0 = time.perf_counter()
        mppi.engine.run(data, controls)
        raws.append(time.perf_counter() - t0)
    mppi.close()
    world.close()
    it, raw = float(np.median(iters)), float(np.median(raws))
    steps = args.samples * mppi.steps
    print(f"K={args.samples} horizon={args.horizon}s ({mppi.steps} steps of {planning.model.opt.timestep}s), "
          f"{mppi.engine.nthread} threads, {args.iters} iterations (median; this machine's speed drifts under load)")
    print(f"iteration {it * 1000:.1f} ms (p10 {np.percentile(iters, 10) * 1000:.1f}, p90 {np.percentile(iters, 90) * 1000:.1f}),"
          f" raw rollout of the same controls {raw * 1000:.1f} ms (inside the iteration {np.median(inside) * 1000:.1f} ms),"
          f" {steps / raw:.0f} planning steps/s")
    print(json.dumps({"hz": round(1 / it, 2), "samples": args.samples, "horizon_s": args.horizon,
                      "overhead": round(it / raw, 3), "iteration_ms": round(it * 1000, 2),
                      "rollout_ms": round(raw * 1000, 2), "threads": mppi.engine.nthread}))


if __name__ == "__main__":
    main()
