"""Peg-insertion speed on this machine: trial wall time and framework step rate vs raw MuJoCo.

    .venv/bin/python bench/bench_peg.py [--trials 20] [--seed 0]

(a) Wall time of baseline trials through `run_trial` (shapes mixed, condition "all"); their system-A tables
    (`kintsugi.campaign.tables.tables_for`, as `kintsugi bench peg-insertion` prints them) at the end.
(b) Physics steps per wall-second while the CF skills run (`execute_skill`, rendering
    excluded), against a tight `mujoco.mj_step` loop on the same MjModel/MjData replaying the
    same base trajectory (same contacts, same number of steps; the replay must end in the same state, bit for bit).
Prints Markdown tables (`--page docs/benchmarks-peg.md` writes them into the benchmark page); targets: <= 1.5 s per trial, overhead <= 2x raw.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np

from kintsugi.campaign.render import print_tables
from kintsugi.campaign.tables import tables_for
from kintsugi.core.plugins import load_builtins
from kintsugi.worlds.peg.conditions import sample_params
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import full_goals, load_goals
from kintsugi.worlds.peg.skills import SEQUENCE, execute_skill
from kintsugi.worlds.peg.world import HOME_POSE, PegWorld
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

SHAPES = ("round", "square", "rectangle")
TARGET_TRIAL_S = 1.5
TARGET_OVERHEAD = 2.0


def _percentile(xs: list[float], q: float) -> float:
    return float(np.percentile(np.array(xs), q))


def bench_trials(n: int, seed0: int) -> tuple[list[float], list[int], int, list]:
    walls, steps, successes, records = [], [], 0, []
    for i in range(n):
        spec = TrialSpec(task="peg-insertion", method="baseline", variant=SHAPES[i % len(SHAPES)],
                         condition="all", seed=seed0 + i)
        rec = run_trial(spec)
        if rec.error:
            raise SystemExit(f"trial {spec.key} failed: {rec.error}")
        walls.append(rec.wall_time)
        steps.append(rec.physics_steps)
        successes += rec.success
        records.append(rec)
    return walls, steps, successes, records


def bench_step_rate(shape: str, seed: int, repeats: int) -> dict[str, float]:
    """Framework vs raw stepping on one world (best of `repeats` to dodge scheduler noise)."""
    cfg = PegTaskConfig()
    params = sample_params(cfg, shape, "all", seed)
    goals = full_goals(load_goals(), HOME_POSE)

    # Framework: the skills as methods run them; render time measured and subtracted.
    best_fw, n_steps, render_s = float("inf"), 0, 0.0
    for _ in range(repeats):
        world = PegWorld(cfg, params)
        world.render()  # create the GL context outside the timing
        real_render, spent = world.render, [0.0]

        def timed_render(real=real_render, spent=spent) -> np.ndarray:  # noqa: ANN001
            t = time.perf_counter()
            img = real()
            spent[0] += time.perf_counter() - t
            return img

        world.render = timed_render  # type: ignore[method-assign]
        t0 = time.perf_counter()
        for skill in SEQUENCE:
            execute_skill(world, skill, goals[skill])
        total = time.perf_counter() - t0
        if total - spent[0] < best_fw:
            best_fw, n_steps, render_s = total - spent[0], world.steps, spent[0]
        world.close()

    # Record the base trajectory (mocap per physics step) with an untimed replay of the same run.
    world = PegWorld(cfg, params)
    world.render = lambda: np.zeros((1, 1, 3), np.uint8)  # type: ignore[method-assign]
    traj: list[tuple[np.ndarray, np.ndarray]] = []
    n_sub = max(1, round(1.0 / cfg.control.rate_hz / world.model.opt.timestep))

    def record(w: PegWorld) -> None:  # called after each control tick with the mocap it stepped
        traj.append((w.data.mocap_pos.copy(), w.data.mocap_quat.copy()))

    for skill in SEQUENCE:
        execute_skill(world, skill, goals[skill], on_tick=record)
    assert len(traj) * n_sub == world.steps == n_steps, (len(traj) * n_sub, world.steps, n_steps)

    final_qpos = world.data.qpos.copy()

    # Raw: the same MjModel/MjData, reset, one mj_step per physics step in a tight loop.
    m, d = world.model, world.data
    best_raw = float("inf")
    replay_err = 0.0
    for _ in range(repeats):
        mujoco.mj_resetData(m, d)
        d.mocap_pos[:], d.mocap_quat[:] = traj[0]
        mujoco.mj_forward(m, d)
        step = mujoco.mj_step
        t0 = time.perf_counter()
        for pos, quat in traj:
            d.mocap_pos[:] = pos
            d.mocap_quat[:] = quat
            for _ in range(n_sub):
                step(m, d)
        best_raw = min(best_raw, time.perf_counter() - t0)
        replay_err = max(replay_err, float(np.max(np.abs(d.qpos - final_qpos))))
    world.close()
    if replay_err > 1e-9:  # the raw loop must do the same physics (same contacts), not a cheaper one
        raise SystemExit(f"raw replay of {shape} diverged from the framework run by {replay_err:.3g}")
    return {"steps": n_steps, "framework_s": best_fw, "raw_s": best_raw, "render_s": render_s,
            "framework_rate": n_steps / best_fw, "raw_rate": n_steps / best_raw}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=20, help="baseline trials for the wall-time figure")
    ap.add_argument("--seed", type=int, default=0, help="first trial seed")
    ap.add_argument("--repeats", type=int, default=5, help="repeats of the step-rate run (best is kept)")
    ap.add_argument("--page", help="also write the tables into this benchmark page (e.g. docs/benchmarks-peg.md)")
    args = ap.parse_args()
    load_builtins()

    print(f"machine: {platform.platform()} | {platform.processor() or platform.machine()} | "
          f"{os.cpu_count()} CPUs | Python {sys.version.split()[0]} | mujoco {mujoco.__version__}")
    run_trial(TrialSpec(task="peg-insertion", method="baseline", variant="round", condition="none", seed=0))  # warm-up

    walls, steps, successes, records = bench_trials(args.trials, args.seed)
    med, p90 = statistics.median(walls), _percentile(walls, 90)
    rates = [bench_step_rate(s, args.seed, args.repeats) for s in SHAPES]
    fw_rate = sum(r["steps"] for r in rates) / sum(r["framework_s"] for r in rates)
    raw_rate = sum(r["steps"] for r in rates) / sum(r["raw_s"] for r in rates)
    overhead = raw_rate / fw_rate

    lines: list[str] = []

    def out(text: str = "") -> None:
        print(text)
        lines.extend(text.split("\n"))

    out(f"\n{args.trials} baseline trials (round/square/rectangle, condition all, seeds {args.seed}.."
          f"{args.seed + args.trials - 1}): {successes}/{args.trials} ground-truth successes, "
          f"{statistics.mean(steps):.0f} physics steps per trial on average "
          f"({statistics.mean(steps) * PegTaskConfig().sim.timestep_s:.2f} s simulated)\n")
    out("| figure | value | target | verdict |")
    out("|---|---|---|---|")
    out(f"| trial wall time, median | {med:.3f} s | <= {TARGET_TRIAL_S} s | "
          f"{'ok' if med <= TARGET_TRIAL_S else 'MISSED'} |")
    out(f"| trial wall time, p90 | {p90:.3f} s | <= {TARGET_TRIAL_S} s | "
          f"{'ok' if p90 <= TARGET_TRIAL_S else 'MISSED'} |")
    out(f"| trial wall time, max | {max(walls):.3f} s | | |")
    out(f"| raw mj_step rate | {raw_rate:,.0f} steps/s | | |")
    out(f"| framework step rate (skills, no render) | {fw_rate:,.0f} steps/s | | |")
    out(f"| framework overhead (raw / framework) | {overhead:.2f}x | <= {TARGET_OVERHEAD}x | "
          f"{'ok' if overhead <= TARGET_OVERHEAD else 'MISSED'} |")
    out(f"| real-time factor (framework, no render) | {fw_rate * PegTaskConfig().sim.timestep_s:.1f}x | | |")
    out("\nper shape (one run of the taught skills under condition all, seed "
          f"{args.seed}, best of {args.repeats}):\n")
    out("| shape | steps | framework s | raw s | render s (5 frames) | overhead |")
    out("|---|---|---|---|---|---|")
    for shape, r in zip(SHAPES, rates):
        out(f"| {shape} | {r['steps']} | {r['framework_s']:.4f} | {r['raw_s']:.4f} | {r['render_s']:.4f} | "
              f"{r['framework_s'] / r['raw_s']:.2f}x |")
    print()
    print_tables(tables_for("peg-insertion", records))
    if args.page:
        try:
            from bench.pages import Block, command_line, write_block
        except ModuleNotFoundError:  # run as a script: bench/ is on the path
            from pages import Block, command_line, write_block

        print(f"page: {write_block(args.page, Block('bench_peg', command_line(), lines))}")



if __name__ == "__main__":
    main()
