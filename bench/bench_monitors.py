"""Monitor evaluation cost per control step (Eq. 12), the issue's target: <= 0.2 ms for ~10 monitors.

    .venv/bin/python bench/bench_monitors.py            # 10 monitors, 20,000 steps
    .venv/bin/python bench/bench_monitors.py --monitors 30 --steps 50000

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--monitors", type=int, default=10)
    ap.add_argument("--steps", type=int, default=20_000)
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
    print(f"machine: {platform.platform()} | {cpu_model()} | "
          f"{os.cpu_count()} CPUs | Python {sys.version.split()[0]} | load avg {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
