"""System identification from a wrong prior on system C's tasks: how close, in how many cycles.

A cycle = one attempt of the expert-FSM costs planned in the current beliefs (the scene is
reset before each), then a fit of the target object's mass and friction on every logged
window so far, written back into the planning world. The prior is the nominal physics x
sysid.prior_mass_scale (8) and x sysid.prior_friction_scale (1.8). Cycles stop when no
belief moved more than 5 % or after 4. Errors are |belief - truth| / truth (the truth is
read here, by the benchmark, only to score).

Last line: one JSON object with mass_error, friction_error (worst over the trials and
tasks run), cycles (most used), and per-task figures.
Usage: .venv/bin/python bench/bench_sysid.py [--tasks push-pick-board,push-force] [--seeds 0,1,2]
(any contact task works: its `target` object is fitted; T1 and T4 are the issue's targets)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import kintsugi  # noqa: E402,F401 - sets MUJOCO_GL
import kintsugi.methods.builtin  # noqa: E402,F401
from bench_mppi import machine  # noqa: E402
from kintsugi.tasks import TASKS, load_all  # noqa: E402
from kintsugi.tasks.contact.execute import run_attempt  # noqa: E402
from kintsugi.tasks.contact.experts import expert_design  # noqa: E402
from kintsugi.tasks.contact.identify import BeliefFitter  # noqa: E402
from kintsugi.tasks.contact.robot import ContactRobot  # noqa: E402
from kintsugi.tasks.contact.world import PlanningWorld  # noqa: E402
from kintsugi.trial import TrialLog, TrialSpec  # noqa: E402

MAX_CYCLES = 4
CONVERGED = 0.05


def one(task_name: str, seed: int) -> dict:
    from kintsugi.methods.contact import MPPISysId

    task = TASKS.get(task_name).factory()
    cfg = task.config({})
    world, scorer, setup = task.build(cfg, "random", seed)
    spec = TrialSpec(task=task_name, method="mppi-sysid", variant="default", condition="random", seed=seed)
    ctx = task.context(cfg, setup, False, spec)  # no oracle: the method's own view
    obj = task.spec.target
    planning = PlanningWorld(cfg, ctx.known, MPPISysId(ctx).prior())
    fitter = BeliefFitter(planning, obj, cfg.sysid.mass_bounds_kg, cfg.sysid.friction_bounds)
    robot = ContactRobot(world, watchers=[scorer.watch], on_restart=[scorer.reset])
    truth = setup.truth[obj]
    prior = planning.physics_of(obj)
    beliefs = [prior]
    t0 = time.perf_counter()
    for cycle in range(MAX_CYCLES):
        if cycle:
            robot.restart()
        robot.new_log()
        result, _ = run_attempt(cfg, robot, planning, expert_design(task_name, True)(ctx), TrialLog(),
                                seed=seed + 1000 * cycle)
        fitter.add(robot.new_log())
        phys, _ = fitter.fit()
        beliefs.append(phys)
        moved = max(abs(phys.mass_kg / beliefs[-2].mass_kg - 1), abs(phys.friction / beliefs[-2].friction - 1))
        print(f"  {task_name} seed {seed} cycle {cycle + 1}: attempt {'reached' if result.reached else 'failed'}, "
              f"{len(fitter.logs)} windows -> mass {phys.mass_kg:.3f} (truth {truth.mass_kg:.3f}), friction "
              f"{phys.friction:.3f} (truth {truth.friction:.3f})", flush=True)
        if cycle and moved <= CONVERGED:
            break
    world.close()
    last = beliefs[-1]
    return {"task": task_name, "seed": seed, "cycles": len(beliefs) - 1, "wall_s": round(time.perf_counter() - t0, 1),
            "prior_mass_error": abs(prior.mass_kg - truth.mass_kg) / truth.mass_kg,
            "prior_friction_error": abs(prior.friction - truth.friction) / truth.friction,
            "mass_error": abs(last.mass_kg - truth.mass_kg) / truth.mass_kg,
            "friction_error": abs(last.friction - truth.friction) / truth.friction}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", default="push-pick-board,push-force")
    ap.add_argument("--seeds", default="0,1,2")
    args = ap.parse_args()
    print("machine:", machine())
    load_all()
    rows = [one(t, int(s)) for t in args.tasks.split(",") for s in args.seeds.split(",")]
    for r in rows:
        print(f"{r['task']} seed {r['seed']}: prior error mass {r['prior_mass_error']:.0%} friction "
              f"{r['prior_friction_error']:.0%} -> mass {r['mass_error']:.1%} friction {r['friction_error']:.1%} "
              f"after {r['cycles']} cycles ({r['wall_s']} s wall)")
    print(json.dumps({"mass_error": round(max(r["mass_error"] for r in rows), 4),
                      "friction_error": round(max(r["friction_error"] for r in rows), 4),
                      "cycles": max(r["cycles"] for r in rows), "trials": len(rows),
                      "per_trial": [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}
                                    for r in rows]}))


if __name__ == "__main__":
    main()
