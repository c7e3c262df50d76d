"""System identification from a wrong prior on system C's tasks: how close, in how many cycles.

A cycle = one attempt of the expert-FSM costs planned in the current beliefs (the scene is
reset before each), then a fit of the target object's mass and friction on every logged
window so far, written back into the planning world. The prior is mppi-sysid's: each known
model's volume at sysid.prior_density_kg_m3 (steel), friction sysid.prior_friction. Cycles stop when no
belief moved more than 5 % or after 4. Errors are |belief - truth| / truth (the truth is
read here, by the benchmark, only to score).

Last line: one JSON object with mass_error, friction_error (worst over the trials and
tasks run), cycles (most used), and per-task figures.
Usage: .venv/bin/python bench/bench_sysid.py [--tasks push-pick-board,push-force] [--seeds 0,1,2]
(any contact task works: its `target` object is fitted)

The sensitivity study (CoRAL's T1 study): `--prior coral --all-cycles --seeds 0-9`. The prior is then
the physics-priors role's guess (embedded backend: a material table times the object's known volume,
never the truth); all four cycles run whatever happens, and the study prints the mean absolute error
of mass (kg) and friction before and after the refinement cycles, and the ground-truth success of the
first and the last attempt (each trial's board mass and friction are drawn from the task's ranges).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import kintsugi  # noqa: E402,F401 - sets MUJOCO_GL
import kintsugi.methods.builtin  # noqa: E402,F401
from bench_mppi import machine  # noqa: E402
from kintsugi.core.plugins import load_builtins  # noqa: E402
from kintsugi.core.registry import TASKS  # noqa: E402
from kintsugi.methods.mppi.execute import run_attempt  # noqa: E402
from kintsugi.methods.expert.designs import expert_design  # noqa: E402
from kintsugi.methods.mppi.identify import BeliefFitter  # noqa: E402
from kintsugi.worlds.contact.robot import ContactRobot  # noqa: E402
from kintsugi.worlds.contact.world import PlanningWorld  # noqa: E402
from kintsugi.core.log import TrialLog  # noqa: E402
from kintsugi.core.record import ReasonerSettings  # noqa: E402

MAX_CYCLES = 4
CONVERGED = 0.05


def coral_prior(ctx) -> dict:  # noqa: ANN001 - a ContactContext
    """The physics-priors role's guess, from the labels and known sizes only (as coral asks it)."""
    from kintsugi.methods.coral.views import object_views
    from kintsugi.reasoning import make_reasoner
    from kintsugi.methods.coral.types import PriorsRequest
    from kintsugi.methods.coral.priors import ask_priors
    from kintsugi.worlds.contact.objects import Physics

    reply, _ = ask_priors(make_reasoner(ctx.reasoner), PriorsRequest(task=ctx.task_text, objects=object_views(ctx.known)))
    return {k: Physics(mass_kg=v.mass_kg, friction=v.friction) for k, v in reply.objects.items()}


def one(task_name: str, seed: int, prior: str = "scaled", all_cycles: bool = False) -> dict:
    from kintsugi.methods.expert.method import MPPISysId

    task = TASKS.get(task_name).factory()
    cfg = task.config({})
    world, scorer, setup = task.build(cfg, "random", seed)
    ctx = task.context(cfg, setup, False, ReasonerSettings(), seed)  # no oracle: the method's own view
    obj = task.spec.target
    beliefs0 = MPPISysId(ctx).prior() if prior == "scaled" else MPPISysId(ctx).prior() | coral_prior(ctx)
    planning = PlanningWorld(cfg, ctx.known, beliefs0)
    fitter = BeliefFitter(planning, obj, cfg.sysid.mass_bounds_kg, cfg.sysid.friction_bounds)
    robot = ContactRobot(world, watchers=[scorer.watch], on_restart=[scorer.reset])
    truth = setup.truth[obj]
    prior = planning.physics_of(obj)
    beliefs = [prior]
    successes = []
    t0 = time.perf_counter()
    for cycle in range(MAX_CYCLES):
        if cycle:
            robot.restart()
        robot.new_log()
        result, _ = run_attempt(cfg, robot, planning, expert_design(task_name, True)(replace(ctx, seed=seed)), TrialLog(),
                                seed=seed + 1000 * cycle)
        successes.append(bool(scorer.finish(world)[0]))
        fitter.add(robot.new_log())
        phys, _ = fitter.fit()
        beliefs.append(phys)
        moved = max(abs(phys.mass_kg / beliefs[-2].mass_kg - 1), abs(phys.friction / beliefs[-2].friction - 1))
        print(f"  {task_name} seed {seed} cycle {cycle + 1}: attempt {'reached' if result.reached else 'failed'}, "
              f"{len(fitter.logs)} windows -> mass {phys.mass_kg:.3f} (truth {truth.mass_kg:.3f}), friction "
              f"{phys.friction:.3f} (truth {truth.friction:.3f})", flush=True)
        if cycle and moved <= CONVERGED and not all_cycles:
            break
    world.close()
    last = beliefs[-1]
    return {"task": task_name, "seed": seed, "cycles": len(beliefs) - 1, "wall_s": round(time.perf_counter() - t0, 1),
            "prior_mass_error": abs(prior.mass_kg - truth.mass_kg) / truth.mass_kg,
            "prior_friction_error": abs(prior.friction - truth.friction) / truth.friction,
            "mass_error": abs(last.mass_kg - truth.mass_kg) / truth.mass_kg,
            "friction_error": abs(last.friction - truth.friction) / truth.friction,
            "truth": {"mass_kg": truth.mass_kg, "friction": truth.friction},
            "prior": {"mass_kg": prior.mass_kg, "friction": prior.friction},
            "fitted": {"mass_kg": last.mass_kg, "friction": last.friction}, "success": successes}


def seeds_of(text: str) -> list[int]:
    """'0,1,2' or '0-9' (or a mix: '0-3,7')."""
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += list(range(int(lo), int(hi) + 1)) if hi else [int(lo)]
    return out


def sensitivity(rows: list[dict]) -> dict:
    """Mean absolute errors (kg, friction) of the priors and of the last fit, and the first and last attempt's
    ground-truth success (x/n with a Wilson 95 % interval)."""
    from kintsugi.campaign.stats import wilson_interval as wilson

    def mae(which: str, key: str) -> float:
        return float(sum(abs(r[which][key] - r["truth"][key]) for r in rows) / len(rows))

    def rate(k: int) -> str:
        won = sum(r["success"][k] for r in rows)
        lo, hi = wilson(won, len(rows))
        return f"{won}/{len(rows)} [{lo:.0%}-{hi:.0%}]"

    return {"mass_mae_prior_kg": round(mae("prior", "mass_kg"), 4), "mass_mae_after_kg": round(mae("fitted", "mass_kg"), 4),
            "friction_mae_prior": round(mae("prior", "friction"), 4), "friction_mae_after": round(mae("fitted", "friction"), 4),
            "success_first": rate(0), "success_last": rate(-1)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", default="push-pick-board,push-force")
    ap.add_argument("--seeds", default="0,1,2", help="comma-separated, or a range such as 0-9")
    ap.add_argument("--prior", choices=("scaled", "coral"), default="scaled",
                    help="scaled: mppi-sysid's prior (steel density x known volume, friction 0.9); coral: the physics-priors role")
    ap.add_argument("--all-cycles", action="store_true", help="run all four cycles (the sensitivity study)")
    args = ap.parse_args()
    print("machine:", machine())
    load_builtins()
    rows = [one(t, s, args.prior, args.all_cycles) for t in args.tasks.split(",") for s in seeds_of(args.seeds)]
    for r in rows:
        print(f"{r['task']} seed {r['seed']}: prior error mass {r['prior_mass_error']:.0%} friction "
              f"{r['prior_friction_error']:.0%} -> mass {r['mass_error']:.1%} friction {r['friction_error']:.1%} "
              f"after {r['cycles']} cycles ({r['wall_s']} s wall)")
    study = sensitivity(rows) if args.all_cycles else {}
    if study:
        print(f"sensitivity ({len(rows)} trials, prior {args.prior}): mass MAE {study['mass_mae_prior_kg']:.3f} -> "
              f"{study['mass_mae_after_kg']:.3f} kg, friction MAE {study['friction_mae_prior']:.3f} -> "
              f"{study['friction_mae_after']:.3f}; success first attempt {study['success_first']}, "
              f"last {study['success_last']}")
    print(json.dumps({"mass_error": round(max(r["mass_error"] for r in rows), 4),
                      "friction_error": round(max(r["friction_error"] for r in rows), 4),
                      "cycles": max(r["cycles"] for r in rows), "trials": len(rows), "prior": args.prior, **study,
                      "per_trial": [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}
                                    for r in rows]}))


if __name__ == "__main__":
    main()
