"""AgentChord compile time per tabletop task and monitor cost per control step, on this machine.

    MUJOCO_GL=egl .venv/bin/python bench/bench_agentchord.py [--repeats 5] [--steps 20000]

(a) Compile = composer + arranger (embedded reasoner) + keyframes of the free moves, from the first perceived
    observation of each registered tabletop task (condition `none`); median and max over repeats. A task whose
    goal the embedded composer cannot plan is listed with its one-line reason. Target: <= 10 s per task.
(b) Monitor cost: `MonitorBank.step` on the compiled pour-single graph, for the edge with the most monitors and
    for all monitors of the graph at once, fed perceived features of the first observation (perception itself
    excluded: it is the robot's cost, paid once per action). Target: <= 0.2 ms per control step.
Figures are wall-clock on a shared 2-core machine: noisy; compare medians.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import kintsugi  # noqa: E402,F401 - sets MUJOCO_GL before mujoco is imported
from kintsugi.core.errors import KintsugiError  # noqa: E402
from kintsugi.methods.agentchord.compile import compile_graph  # noqa: E402
from kintsugi.methods.agentchord.keyframes import TabletopKeyframes  # noqa: E402
from kintsugi.methods.agentchord.method import AgentChord  # noqa: E402
from kintsugi.methods.agentchord.observe import features  # noqa: E402
from kintsugi.reasoning import make_reasoner  # noqa: E402
from kintsugi.reasoning.base import RecordingReasoner  # noqa: E402
from kintsugi.taskgraph.monitor import MonitorBank  # noqa: E402
from kintsugi.core.record import ReasonerSettings


def compile_once(task, robot, cfg):  # noqa: ANN001, ANN201
    reasoner = RecordingReasoner(make_reasoner(ReasonerSettings()))
    t0 = time.perf_counter()
    obs = robot.observation(images=False)
    t1 = time.perf_counter()
    compiled = compile_graph(reasoner, task.spec, obs, cfg=cfg)
    AgentChord._compile_keyframes(compiled, TabletopKeyframes(cfg), obs)
    t2 = time.perf_counter()
    return compiled, t1 - t0, t2 - t1


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--steps", type=int, default=20000)
    args = ap.parse_args()
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS
    from kintsugi.worlds.tabletop.robot import TabletopRobot

    load_builtins()
    pour = None
    print("(a) compile per task (composer + arranger + keyframes; first perception shown apart)")
    for entry in TASKS:
        if "system-b" not in entry.tags:
            continue
        task = entry.factory()
        cfg = task.config({})
        world, *_ = task.build(cfg, "none", 0)
        robot = TabletopRobot(world)
        try:
            runs = [compile_once(task, robot, cfg) for _ in range(args.repeats)]
        except KintsugiError as exc:
            print(f"  {entry.name:16s} not compiled: {str(exc).splitlines()[0][:140]}")
            world.close()
            continue
        comp = [r[2] for r in runs]
        g = runs[0][0].graph
        print(f"  {entry.name:16s} compile median {statistics.median(comp):.3f} s, max {max(comp):.3f} s "
              f"(perception {statistics.median(r[1] for r in runs):.3f} s); {len(g.nodes)} nodes, {len(g.edges)} "
              f"edges, {len(g.monitors())} monitors")
        if entry.name == "pour-single":
            pour = (runs[0][0], robot)
        else:
            world.close()
    if pour is None:
        return
    compiled, robot = pour
    f = features(robot)
    g = compiled.graph
    busiest = max((e for e in g.edges if e.monitors), key=lambda e: len(e.monitors))
    print(f"(b) monitor cost per control step ({args.steps} steps; perceived features of the first observation)")
    for label, monitors in ((f"edge {busiest.id} ({len(busiest.monitors)} monitors)", busiest.monitors),
                            (f"all {len(g.monitors())} monitors of the graph", [m for _, m in g.monitors()])):
        bank = MonitorBank(monitors, f)
        times = []
        for _ in range(args.steps):
            t = time.perf_counter()
            bank.step(f)
            times.append(time.perf_counter() - t)
        times.sort()
        print(f"  {label}: median {1e3 * statistics.median(times):.4f} ms, p99 {1e3 * times[int(0.99 * len(times))]:.4f} ms")


if __name__ == "__main__":
    main()
