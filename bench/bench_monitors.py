"""Monitor evaluation cost per control step (Eq. 12), the issue's target: <= 0.2 ms for ~10 monitors.

    .venv/bin/python bench/bench_monitors.py            # 10 monitors, 20,000 steps
    .venv/bin/python bench/bench_monitors.py --monitors 30 --steps 50000
    MUJOCO_GL=egl .venv/bin/python bench/bench_monitors.py --live   # + the conductor's real per-step read

`--live` also times what the conductor does every control step on the real tabletop robot while it lifts
and carries a grasped bottle: the per-step feature read (`grip_sense`: encoders and finger pads, no
images) of both arms plus `MonitorBank.step` over the proprioceptive monitors (drop by pad touch, missed
grasp by opening), and, for comparison, one full perceived-feature read (renders) as a sub-goal costs.

The features are shaped like perception's (numpy vectors, extremes in a dict) and change
every step, so nothing is cached; the time covers `MonitorBank.step` only (features are made
beforehand). Prints the median and 99th percentile per step and the machine.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kintsugi.taskgraph.features import ArmState, Features  # noqa: E402
from kintsugi.taskgraph.model import Monitor  # noqa: E402
from kintsugi.taskgraph.monitor import MonitorBank  # noqa: E402


@dataclass
class Obj:
    centroid: np.ndarray
    axis: np.ndarray
    n_points: int
    extremes: dict = field(default_factory=dict)


CHECKS = [  # one of each Appendix C-G family, then repeats with other objects
    {"kind": "drift", "point": {"entity": "cup"}, "tol": 0.03, "axes": "xy"},
    {"kind": "upright", "object": "bottle", "tol_deg": 20},
    {"kind": "not_grasped", "arm": "right", "min_opening": 0.01},
    {"kind": "detached", "arm": "right", "object": "bottle", "tol": 0.08},
    {"kind": "visibility", "object": "bottle", "n_min": 50},
    {"kind": "misaligned", "a": {"entity": "bottle", "feature": "top"}, "b": {"entity": "cup"}, "tol": 0.03},
    {"kind": "above", "a": {"entity": "bottle"}, "b": {"entity": "cup", "feature": "top"}, "min_gap": 0.05},
    {"kind": "in_region", "point": {"entity": "plate"}, "lo": [-0.5, -0.5, 0.0], "hi": [0.5, 0.5, 0.3]},
    {"kind": "touching", "arm": "right", "object": "bottle"},
    {"kind": "near", "a": {"entity": "left"}, "b": {"entity": "plate", "along": 0.5}, "tol": 0.5},
]


def features(rng: np.random.Generator, n: int) -> list[Features]:
    out = []
    for _ in range(n):
        objs = {}
        for name, c in (("cup", (0.4, 0.0, 0.05)), ("bottle", (0.4, 0.0, 0.3)), ("plate", (0.5, 0.2, 0.01))):
            centroid = np.asarray(c) + rng.normal(0, 0.002, 3)
            axis = np.array([0.0, 0.0, 1.0]) + rng.normal(0, 0.02, 3)
            top, bottom = centroid + [0, 0, 0.1], centroid - [0, 0, 0.1]
            objs[name] = Obj(centroid, axis / np.linalg.norm(axis), int(rng.integers(200, 400)),
                             {"top": top, "bottom": bottom, "axis_pos": top, "axis_neg": bottom})
        arms = {"right": ArmState(eef=objs["bottle"].centroid + rng.normal(0, 0.002, 3), opening=0.04, closed=True,
                                  touching=frozenset({"bottle"})),
                "left": ArmState(eef=np.array([0.4, 0.3, 0.3]), opening=0.08)}
        out.append(Features(objects=objs, arms=arms))
    return out


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def live() -> None:
    import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
    from kintsugi.worlds.tabletop.config import TabletopConfig
    from kintsugi.worlds.tabletop.robot import TabletopRobot
    from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld

    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"],
                          {"bottle": StartPose(x=0.40, y=-0.25), "cup": StartPose(x=0.46, y=0.0)})
    robot = TabletopRobot(world)
    robot.execute({"action": "grasp", "arm": "right", "obj": "bottle"})
    monitors = [Monitor(id="drop", failure_mode="drop", check={"kind": "touching", "arm": "right", "object": "bottle"},
                        margin=0.0, window=3, recovery=None),
                Monitor(id="missed", failure_mode="missed_grasp", check={"kind": "not_grasped", "arm": "right",
                        "min_opening": 0.01}, margin=0.0, window=3, recovery=None)]
    bank = MonitorBank(monitors)
    read, evaluate, fired = [], [], []

    def watch(step) -> bool:  # noqa: ANN001 - a ControlStep
        t0 = time.perf_counter()
        f = Features(arms={a: robot.grip_sense(a) for a in ("left", "right")})
        t1 = time.perf_counter()
        fired.append(bank.step(f) is not None)
        evaluate.append(time.perf_counter() - t1)
        read.append(t1 - t0)
        return False
    robot.step_observers.append(watch)
    robot.execute({"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.12)})
    robot.execute({"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.2, 0.0)})
    robot.step_observers.clear()
    t0 = time.perf_counter()
    for _ in range(5):
        robot.features(["bottle", "cup"])
    full = (time.perf_counter() - t0) / 5
    world.close()
    med = lambda xs: statistics.median(xs) * 1e6  # noqa: E731
    print(f"live tabletop, {len(read)} control steps of a carry, {sum(fired)} firings (none expected): "
          f"per-step read (grip_sense x2) median {med(read):.1f} us, monitor evaluation median "
          f"{med(evaluate):.1f} us; one full perceived read (renders, 2 objects) {full * 1e3:.1f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--monitors", type=int, default=10)
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--live", action="store_true", help="also time the per-step read on the tabletop robot")
    args = ap.parse_args()
    monitors = [Monitor(id=f"m{i}", failure_mode="fail", check=CHECKS[i % len(CHECKS)], margin=0.005, window=3,
                        recovery=None) for i in range(args.monitors)]
    feats = features(np.random.default_rng(0), 500)
    bank = MonitorBank(monitors, start=feats[0])
    times, fired = [], 0
    for i in range(args.steps):
        f = feats[i % len(feats)]
        t0 = time.perf_counter()
        fired += bank.step(f) is not None
        times.append(time.perf_counter() - t0)
    times.sort()
    med, p99 = statistics.median(times) * 1e6, times[int(0.99 * len(times))] * 1e6
    print(f"monitor bank: {args.monitors} monitors, {args.steps} control steps, {fired} firings (none expected)")
    print(f"per step: median {med:.1f} us, p99 {p99:.1f} us ({med / args.monitors:.2f} us per monitor); "
          f"target <= 200 us per step: {'met' if med <= 200 else 'MISSED'}")
    if args.live:
        live()
    print(f"machine: {platform.platform()} | {cpu_model()} | "
          f"{os.cpu_count()} CPUs | Python {sys.version.split()[0]} | load avg {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
