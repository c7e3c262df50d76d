"""How far the robot's tracked box is from the true box on push-around: the error coral's clearance margin covers.

Runs coral push-around trials (perceived poses, the default) and at every inner tick compares the box the robot
tracks with the simulator's: how far either box's corners reach outside the other (their Hausdorff distance, a
bound on how much any gap measured from the tracked box can be off; a box turned by a symmetry is no error), how
far beyond the hand's path over the last `--age` seconds within reach of the box that reaches (coral's margin is
3 mm beyond it), and the gap to the post measured on each. Prints the percentiles, the smallest tracked gap
while the true box touched the post, and each trial's outcome.

    MUJOCO_GL=egl .venv/bin/python bench/bench_coral_clearance.py --seeds 2
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import kintsugi  # noqa: E402,F401 - before mujoco picks its GL backend
import numpy as np  # noqa: E402

from kintsugi.core.plugins import load_builtins  # noqa: E402
from kintsugi.core.record import TrialSpec  # noqa: E402
from kintsugi.core.runner import run_trial  # noqa: E402
from kintsugi.methods.coral.clearance import _CORNERS, REACH_M, Prism, box_prism, fixture_prism, gap  # noqa: E402
from kintsugi.worlds.contact.world import rotate  # noqa: E402


def _reach(pos_a: np.ndarray, quat_a: np.ndarray, pos_b: np.ndarray, quat_b: np.ndarray, half: tuple) -> float:
    """How far the corners of box a reach outside box b (the same known model at another pose)."""
    corners = rotate(quat_a[None], _CORNERS * np.asarray(half)) + pos_a
    inv = quat_b * np.array([1.0, -1.0, -1.0, -1.0])
    local = rotate(inv[None], corners - pos_b)
    return float(np.max(np.linalg.norm(local - np.clip(local, -np.asarray(half), np.asarray(half)), axis=1)))


def measure(seed: int, method: str, overrides: dict, age_s: float) -> tuple[dict, list[tuple]]:
    rows: list[tuple] = []
    hand: list[tuple[float, np.ndarray, bool]] = []

    def attach(robot, log) -> None:  # noqa: ANN001
        world, observe = robot._world, robot.observe
        fx = world.scene.fixtures["post"]
        post = fixture_prism(tuple(p - h for p, h in zip(fx.pos, fx.half)), tuple(p + h for p, h in zip(fx.pos, fx.half)))
        half = world.scene.geometry["box"].parts[0].half

        def watched():  # noqa: ANN202
            obs = observe()
            seen = obs.objects["box"]
            pos, quat = world.object_pose("box")
            err = max(_reach(seen.pos, seen.quat, pos, quat, half), _reach(pos, quat, seen.pos, seen.quat, half))
            tip = obs.ee[:3].copy()
            box = box_prism(seen.pos, seen.quat, half)
            near = gap(Prism(tip[None, :2], float(tip[2]), float(tip[2])), box) <= REACH_M and tip[2] < box.z_hi
            hand.append((obs.t, tip[:2], near))
            h = [x for x in hand if x[0] >= obs.t - age_s - 1e-9]
            path = float(sum(np.linalg.norm(b[1] - a[1]) for a, b in zip(h, h[1:]) if a[2] or b[2]))
            rows.append((err, gap(box_prism(seen.pos, seen.quat, half), post), gap(box_prism(pos, quat, half), post),
                         world.in_contact("box", "post"), err - path))
            return obs

        robot.observe = watched

    spec = TrialSpec(task="push-around", method=method, variant="default", condition="all", seed=seed,
                     overrides=overrides)
    rec = run_trial(spec, attach=attach)
    return {"seed": seed, "success": rec.success, "verdict": rec.framework_success, "error": rec.error,
            "touched": rec.task_figures.get("touched")}, rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--method", default="coral")
    ap.add_argument("--age", type=float, default=0.15, help="the hand's path over this many seconds (s)")
    ap.add_argument("--set", nargs="*", default=[], help="config overrides key=value")
    args = ap.parse_args()
    load_builtins()
    overrides = dict(kv.split("=", 1) for kv in args.set)
    every: list[tuple] = []
    for seed in args.seeds:
        outcome, rows = measure(seed, args.method, overrides, args.age)
        every += rows
        err = np.array([r[0] for r in rows])
        diff = np.array([r[1] - r[2] for r in rows])
        print(outcome, f"ticks {len(rows)}, box error p99 {np.percentile(err, 99) * 1000:.2f} mm, "
              f"max {err.max() * 1000:.2f} mm; tracked minus true gap to the post {diff.min() * 1000:.2f} to "
              f"{diff.max() * 1000:.2f} mm; beyond the hand's path {max(r[4] for r in rows) * 1000:.2f} mm", flush=True)
    err = np.array([r[0] for r in every])
    diff = np.array([r[1] - r[2] for r in every])
    touched = [r[1] for r in every if r[3]]
    print(f"{len(every)} ticks: box error p50 {np.percentile(err, 50) * 1000:.2f} mm, p99 "
          f"{np.percentile(err, 99) * 1000:.2f} mm, p99.9 {np.percentile(err, 99.9) * 1000:.2f} mm, max "
          f"{err.max() * 1000:.2f} mm, beyond the hand's path over {args.age:g} s at most "
          f"{max(r[4] for r in every) * 1000:.2f} mm; tracked gap minus true gap min {diff.min() * 1000:.2f} mm, max "
          f"{diff.max() * 1000:.2f} mm; ticks touching the post {len(touched)}, largest tracked gap then "
          + (f"{max(touched) * 1000:.2f} mm" if touched else "-"))


if __name__ == "__main__":
    main()
