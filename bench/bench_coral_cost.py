"""Cost code's share of an MPPI iteration on system C's tasks (the budget: at most 10 %): T1-T6 and the tasks whose
costs are composed from the same primitives (slide-puck, roll-cylinder, push-around).

For each task: the embedded formulation's code (checked and probed as in a trial), one MPPI iteration in the
planning world (K = control.samples rollouts), then every stage's cost evaluated on that rollout batch with
the loop's own lazy variables. Times are CPU seconds of this process (all rollout threads counted for MPPI),
medians of `--repeats`; on a shared machine wall times stretch with the load, CPU times much less.
Last line: one JSON object with per-task {stage: share} and `max_share`.
Usage: .venv/bin/python bench/bench_coral_cost.py [--tasks push-force,flip-wall] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402

import kintsugi.methods.builtin  # noqa: E402,F401
from bench_mppi import machine  # noqa: E402
from kintsugi.core.plugins import load_builtins  # noqa: E402
from kintsugi.core.registry import TASKS


def measure(name: str, repeats: int) -> dict[str, float]:
    from kintsugi.control import MPPI
    from kintsugi.methods.coral.env import entry_env, first_env, rollout_env, static_env
    from kintsugi.methods.coral.method import VARIANTS, Coral, probe_limits
    from kintsugi.methods.coral.stages import attractor_of
    from kintsugi.methods.coral.costlib import compose
    from kintsugi.methods.coral.formulate import check_formulation
    from kintsugi.methods.mppi.costs import View, total
    from kintsugi.methods.mppi.execute import mppi_config
    from kintsugi.worlds.contact.robot import ContactRobot
    from kintsugi.worlds.contact.world import PlanningWorld
    from kintsugi.core.record import ReasonerSettings

    task = TASKS.get(name).factory()
    cfg = task.config({})
    world, _, setup = task.build(cfg, "all", 0)
    ctx = task.context(cfg, setup, False, ReasonerSettings(), 0)
    obs = ContactRobot(world).observe()
    req = Coral(ctx, VARIANTS["coral"]).scene_request(obs, {})
    steps = round(cfg.control.horizon_s / cfg.sim.planning_timestep_s)
    plan, program, _ = check_formulation(compose(req), req, cfg.control.samples, steps, probe_limits())
    planning = PlanningWorld(cfg, ctx.known, dict(setup.nominal))
    got: dict = {}

    def keep(batch):  # noqa: ANN001, ANN202
        got["batch"] = batch
        return np.zeros(batch.controls.shape[0])

    mppi = MPPI(planning.model, mppi_config(cfg, 0), keep)
    data = planning.sync(obs.ee, obs.ee_vel, obs.fingers, obs.finger_vel,
                         {k: (o.pos, o.quat, o.lin_vel, o.ang_vel) for k, o in obs.objects.items()}, obs.ctrl, obs.t)
    it = []
    for _ in range(repeats):
        c = time.process_time()
        mppi.step(data)
        it.append(time.process_time() - c)
    batch = got["batch"]
    env0 = {**static_env(ctx.known, cfg), **first_env(obs), **entry_env(obs, ctx.known), "kept": np.asarray(0.0)}
    shares = {"mppi_cpu_ms": round(1000 * statistics.median(it), 2)}
    for spec in plan.stages:
        att = attractor_of(plan, spec.region, cfg.control.attractor_samples, 0)
        ts = []
        for _ in range(repeats):
            view = View(batch, planning.layout, obs)
            c = time.process_time()
            total(program.call(spec.cost, rollout_env(view, ctx.known, env0, att), view.tcp.shape[:2]))
            ts.append(time.process_time() - c)
        shares[spec.name] = round(statistics.median(ts) / statistics.median(it), 4)
    mppi.close()
    world.close()
    return shares


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="push-pick-board,pick-box,pick-clutter,push-force,flip-box,flip-wall,"
                                      "slide-puck,roll-cylinder,push-around")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    load_builtins()
    print(f"machine: {machine()}")
    out = {}
    for name in args.tasks.split(","):
        out[name] = measure(name, args.repeats)
        stages = {k: v for k, v in out[name].items() if k != "mppi_cpu_ms"}
        print(f"{name:14s} MPPI iteration {out[name]['mppi_cpu_ms']:7.1f} ms CPU; cost code share per stage: "
              + ", ".join(f"{k} {v:.1%}" for k, v in stages.items()))
    worst = max(v for s in out.values() for k, v in s.items() if k != "mppi_cpu_ms")
    print(json.dumps({"tasks": out, "max_share": worst}))


if __name__ == "__main__":
    main()
