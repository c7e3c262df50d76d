"""How `kintsugi/worlds/peg/default_goals.json` was taught, and how much margin it has.

    .venv/bin/python bench/teach_goals.py [--span 7.5] [--step 1.5] [--write]
    .venv/bin/python bench/teach_goals.py --set wrist.roll_stiffness=1.5 --shapes round --out goals.json

In the default condition only (peg aligned in the grasp, hole at its nominal place,
nominal friction; never a randomized trial), run approach and contact with the stored
goals, then sweep the fit goal (base y where the tilted tip drops into the hole) and the
align goal (base y that lets the wrist swing the peg upright) on a grid around the stored
values, finish with the stored insert, and score ground truth (tip >= 10 mm deep). The
grid is run by branching MuJoCo states (mj_copyData), so each cell costs only its own
align + insert. Prints, per cell, which shapes insert, and the taught goal's margin to the
nearest failing cell. `--write` stores the most robust cell (largest distance to any
failure, all shapes together) back into the file; without it the file is only read.

For a changed robot or world (`--set`, as on the kintsugi command line), the same sweep
re-teaches: `--out FILE` writes the most robust cell for that config (only if some cell
inserts every swept shape), and `--set control.goals_file=FILE` makes kintsugi use it.
Only the fit and align y goals are swept; approach, contact and insert keep their values.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import KintsugiError
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import DEFAULT_GOALS_FILE, full_goals, load_goals
from kintsugi.worlds.peg.skills import AXES, execute_skill
from kintsugi.worlds.peg.world import HOME_POSE, PegWorld, TrialParams

SHAPES = {"round": "r", "square": "s", "rectangle": "R", "polygon6": "6"}
Y = AXES.index("y")


def _snapshot(world: PegWorld) -> mujoco.MjData:
    snap = mujoco.MjData(world.model)
    mujoco.mj_copyData(snap, world.model, world.data)
    return snap


def _restore(world: PegWorld, snap: mujoco.MjData) -> None:
    mujoco.mj_copyData(world.data, world.model, snap)


def sweep_shape(cfg_json: str, shape: str, goals: dict[str, dict[str, float]], fits: list[float],
                aligns: list[float]) -> dict[tuple[float, float], float]:
    """Tip depth (mm) for every (fit y, align y) cell; 0 or less where ground truth says not inserted."""
    world = PegWorld(PegTaskConfig.model_validate_json(cfg_json), TrialParams(shape=shape))  # the default condition
    world.render = lambda: np.zeros((1, 1, 3), np.uint8)  # type: ignore[method-assign] - images unused
    targets = full_goals(goals, HOME_POSE)
    for skill in ("approach", "contact"):
        execute_skill(world, skill, targets[skill])
    after_contact = _snapshot(world)
    depth: dict[tuple[float, float], float] = {}
    for fy in fits:
        _restore(world, after_contact)
        fit = targets["fit"].copy()
        fit[Y] = fy / 1000
        execute_skill(world, "fit", fit)
        after_fit = _snapshot(world)
        for ay in aligns:
            _restore(world, after_fit)
            align = fit.copy()
            align[Y] = ay / 1000
            execute_skill(world, "align", align)
            insert = align.copy()
            insert[AXES.index("z")] = targets["insert"][AXES.index("z")]
            execute_skill(world, "insert", insert)
            truth = world.ground_truth()
            depth[(fy, ay)] = truth.tip_depth_mm if truth.success else min(truth.tip_depth_mm, 0.0)
    world.close()
    return depth


def _grid(centre: float, span: float, step: float) -> list[float]:
    n = int(round(span / step))
    return [round(centre + k * step, 3) for k in range(-n, n + 1)]


def _margin(ok: dict[tuple[float, float], bool], at: tuple[float, float]) -> float:
    """Distance (mm) from `at` to the nearest failing cell; inf if none fails in the grid."""
    fails = [np.hypot(f - at[0], a - at[1]) for (f, a), good in ok.items() if not good]
    return float(min(fails)) if fails else float("inf")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--span", type=float, default=7.5, help="sweep +- this many mm around each stored goal")
    ap.add_argument("--step", type=float, default=1.5, help="grid step (mm)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (one shape each)")
    ap.add_argument("--write", action="store_true", help="store the most robust cell in default_goals.json")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="config override, as on the kintsugi command line (repeatable)")
    ap.add_argument("--shapes", default=",".join(SHAPES), help=f"comma-separated shapes ({', '.join(SHAPES)})")
    ap.add_argument("--out", help="write the goals with the most robust cell to this file (for control.goals_file)")
    args = ap.parse_args()
    try:
        cfg = apply_overrides(PegTaskConfig(), args.sets)
        goals = load_goals(cfg.control.goals_file)
    except KintsugiError as exc:
        raise SystemExit(f"error: {exc}") from None
    shapes = {s: SHAPES.get(s, s[-1]) for s in args.shapes.split(",") if s}
    if args.write and (args.sets or set(shapes) != set(SHAPES)):
        raise SystemExit("error: --write stores the shipped defaults (default config, every shape); use --out FILE")
    taught = (goals["fit"]["y"], goals["align"]["y"])
    fits, aligns = _grid(taught[0], args.span, args.step), _grid(taught[1], args.span, args.step)
    print(f"goals file: {cfg.control.goals_file or DEFAULT_GOALS_FILE}; config changes: {', '.join(args.sets) or 'none'}")
    print("stored goals (mm, deg): " + "; ".join(f"{s} {v}" for s, v in goals.items()))
    print(f"sweep: fit y in [{fits[0]}, {fits[-1]}], align y in [{aligns[0]}, {aligns[-1]}], step {args.step} mm; "
          f"condition none (aligned grasp, nominal hole and friction); shapes {', '.join(shapes)}\n")

    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = {s: pool.submit(sweep_shape, cfg.model_dump_json(), s, goals, fits, aligns) for s in shapes}
        depth = {s: f.result() for s, f in futures.items()}
    elapsed = time.perf_counter() - t0

    ok = {s: {cell: d > 0.0 for cell, d in depth[s].items()} for s in shapes}
    every = {cell: all(ok[s][cell] for s in shapes) for cell in ok[next(iter(shapes))]}
    legend = ", ".join(f"{c} = {s}" for s, c in shapes.items())
    print(f"Cells list the shapes that insert (ground truth G; {legend}; '.' = none); [cell] = stored goal.\n")
    print("| fit y \\ align y | " + " | ".join(f"{a:g}" for a in aligns) + " |")
    print("|---|" + "---|" * len(aligns))
    for fy in fits:
        cells = []
        for ay in aligns:
            text = "".join(c for s, c in shapes.items() if ok[s][(fy, ay)]) or "."
            cells.append(f"[{text}]" if (fy, ay) == taught else text)
        print(f"| **{fy:g}** | " + " | ".join(cells) + " |")

    print("\n| shape | stored goal inserts | depth at stored goal (mm) | cells inserting | "
          "margin to nearest failing cell (mm) | fit-y interval at stored align | align-y interval at stored fit |")
    print("|---|---|---|---|---|---|---|")
    for s in shapes:
        row = [fy for fy in fits if ok[s][(fy, taught[1])]]
        col = [ay for ay in aligns if ok[s][(taught[0], ay)]]
        print(f"| {s} | {'yes' if ok[s][taught] else 'NO'} | {depth[s][taught]:.3f} | "
              f"{sum(ok[s].values())}/{len(ok[s])} | {_margin(ok[s], taught):.2f} | "
              f"{_interval(row, taught[0], args.step)} | {_interval(col, taught[1], args.step)} |")
    m_all = _margin(every, taught)
    # Most robust cell: farthest from any failure, and from the grid's edge (beyond it is unknown).
    edge = {c: min(c[0] - fits[0], fits[-1] - c[0], c[1] - aligns[0], aligns[-1] - c[1]) + args.step for c in every}
    best = max(every, key=lambda c: (every[c], min(_margin(every, c), edge[c]),
                                     -np.hypot(c[0] - taught[0], c[1] - taught[1])))
    print(f"\nall shapes together: stored goal {'inserts' if every[taught] else 'FAILS'}, "
          f"margin {m_all:.2f} mm to the nearest cell where some shape fails; "
          f"most robust cell inside the grid fit y = {best[0]:g}, align y = {best[1]:g} "
          f"(margin {min(_margin(every, best), edge[best]):.2f} mm, grid edge counted as a failure). "
          f"Sweep took {elapsed:.1f} s.")

    targets = [DEFAULT_GOALS_FILE] if args.write else []
    targets += [Path(args.out)] if args.out else []
    if targets and not every[best]:
        raise SystemExit("error: no cell of the grid inserts every swept shape; nothing written "
                         "(widen --span, or teach the approach/contact/insert goals by hand)")
    for path in targets:
        raw = {k: dict(v) for k, v in goals.items()}
        raw["_comment"] = (f"Taught in the default condition with {', '.join(args.sets) or 'the default config'} "
                           f"for {', '.join(shapes)} (bench/teach_goals.py): mm and degrees, wrist-base pose.")
        raw["fit"]["y"], raw["align"]["y"] = best
        try:
            path.write_text(json.dumps(raw, indent=2) + "\n")
        except OSError as exc:
            raise SystemExit(f"error: cannot write {path}: {exc}") from None
        print(f"wrote fit y = {best[0]:g}, align y = {best[1]:g} to {path}"
              + ("" if path == DEFAULT_GOALS_FILE else f"; use it with --set control.goals_file={path}"))


def _interval(values: list[float], at: float, step: float) -> str:
    """The contiguous run of succeeding grid values that contains `at` (or 'none')."""
    if at not in values:
        return "none"
    lo = hi = at
    while round(lo - step, 3) in values:
        lo = round(lo - step, 3)
    while round(hi + step, 3) in values:
        hi = round(hi + step, 3)
    return f"[{lo:g}, {hi:g}] (-{at - lo:g} / +{hi - at:g})"


if __name__ == "__main__":
    main()
