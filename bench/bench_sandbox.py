"""What sandboxed cost code costs inside MPPI (target: <= 10 % of the iteration), and what it refuses.

1. One run, in rotating order so machine drift hits every variant alike: an MPPI step on the
   pusher-and-box scene (K samples, 0.5 s horizon) whose cost is (a) plain numpy written by
   hand and (b) the same cost as model-written source run through the sandbox. Prints medians
   per variant, the sandboxed cost's share of its iteration, the sandbox overhead against the
   hand-written cost and the probe's wall time.
2. The payload suite (`kintsugi.sandbox.payloads`): every hostile or broken program through the
   probe (refused? anything escaped, i.e. the canary file written? the slowest refusal), and the
   state-dependent ones (`IN_LOOP`) through the loop's bound (passed the probe? stopped, and how fast?).

Last line: one JSON object starting with payloads, escapes (payloads accepted or that wrote the canary),
max_seconds (the slowest refusal), then
in_loop, in_loop_stopped, in_loop_max_stop_s, and the MPPI figures.

    .venv/bin/python bench/bench_sandbox.py [--samples 256] [--steps 30] [--no-payloads]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from kintsugi.campaign.report import machine_info  # noqa: E402
from kintsugi.control import MPPI, MPPIConfig  # noqa: E402
from kintsugi.core.errors import SandboxError  # noqa: E402
from kintsugi.sandbox import CostProgram, ProbeLimits, probe  # noqa: E402
from kintsugi.sandbox import payloads as suite  # noqa: E402

GOAL = np.array([0.35, 0.05, 0.025])
PUSHER_BOX = """
<mujoco model="pusher_box">
  <option timestep="0.01" cone="elliptic" impratio="3"/>
  <worldbody>
    <geom name="table" type="plane" size="2 2 0.1" friction="0.1 0.005 0.0001"/>
    <body name="pusher" pos="0 0 0.025">
      <joint name="px" type="slide" axis="1 0 0" damping="1"/>
      <joint name="py" type="slide" axis="0 1 0" damping="1"/>
      <geom name="pusher" type="sphere" size="0.025" mass="1" friction="0.1 0.005 0.0001"/>
      <site name="tip"/>
    </body>
    <body name="box" pos="0.1 0 0.025">
      <freejoint name="box"/>
      <geom name="box" type="box" size="0.05 0.05 0.025" mass="0.5" friction="0.5 0.005 0.0001"/>
    </body>
  </worldbody>
  <actuator>
    <position name="ax" joint="px" kp="400" kv="40" ctrlrange="-0.5 0.5" forcerange="-15 15"/>
    <position name="ay" joint="py" kp="400" kv="40" ctrlrange="-0.5 0.5" forcerange="-15 15"/>
  </actuator>
  <sensor>
    <framepos name="box_pos" objtype="body" objname="box"/>
    <framepos name="tip_pos" objtype="site" objname="tip"/>
  </sensor>
</mujoco>
"""
"""A force-limited planar pusher (a 1 kg sphere on two critically damped position-driven slides) and a flat
0.5 kg box on a low-friction table: the scene of the controller's own tests."""
SOURCE = '''
def push(box, tip, ctrl, goal_pos):
    """Box to the goal, pusher kept behind the box, small commands."""
    to_goal = norm(box - goal_pos)
    behind = norm(tip[..., 0:2] - box[..., 0:2])
    effort = sum(ctrl ** 2, axis=-1)
    return mean(to_goal + 0.3 * relu(behind - 0.08) + 0.001 * effort, axis=-1) + 5 * to_goal[:, -1]
'''


def native(box: np.ndarray, tip: np.ndarray, ctrl: np.ndarray) -> np.ndarray:
    to_goal = np.linalg.norm(box - GOAL, axis=-1)
    behind = np.linalg.norm(tip[..., 0:2] - box[..., 0:2], axis=-1)
    effort = np.sum(ctrl ** 2, axis=-1)
    return np.mean(to_goal + 0.3 * np.maximum(behind - 0.08, 0) + 0.001 * effort, axis=-1) + 5 * to_goal[:, -1]


def payload_suite() -> dict:
    """Every payload through the probe, every in-loop payload through the probe and then the loop's bound."""
    refused = escapes = 0
    slowest = 0.0
    for source in suite.PAYLOADS:
        suite.CANARY.unlink(missing_ok=True)
        t0 = time.perf_counter()
        try:
            probe(source, set(suite.ENV), {"cost": (suite.K,)}, suite.ENV, suite.LIMITS)
        except SandboxError:
            refused += 1
        slowest = max(slowest, time.perf_counter() - t0)
        escapes += int(suite.CANARY.exists())
    stopped, stop_s = 0, 0.0
    for source in suite.IN_LOOP:
        # accepted: fast on its samples (a long wall allowance: on a loaded machine the child starts slowly)
        report = probe(source, set(suite.ENV), {"cost": (suite.K,)}, suite.ENV, ProbeLimits(wall_s=60.0))
        program = CostProgram.compile(source, set(suite.ENV))
        program.probed_s.update(report.seconds_per_call)
        t0 = time.perf_counter()
        try:
            program.bounded_call("cost", suite.LOOP_STATE, (suite.LOOP_K,))
        except SandboxError as exc:
            stopped += int(exc.kind == "overrun")
        stop_s = max(stop_s, time.perf_counter() - t0)
    print(f"payloads: {len(suite.PAYLOADS)}, refused {refused}, escapes {escapes}, slowest refusal {slowest:.2f} s")
    print(f"in-loop payloads (pass the probe, runaway on the loop's states): {len(suite.IN_LOOP)}, stopped {stopped}, "
          f"slowest stop {stop_s:.2f} s (bound: 1 s)")
    return {"payloads": len(suite.PAYLOADS), "escapes": escapes + len(suite.PAYLOADS) - refused,
            "max_seconds": round(slowest, 3), "in_loop": len(suite.IN_LOOP), "in_loop_stopped": stopped,
            "in_loop_max_stop_s": round(stop_s, 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--steps", type=int, default=30, help="MPPI steps per variant")
    ap.add_argument("--no-payloads", action="store_true", help="skip the payload suite")
    args = ap.parse_args()
    source = SOURCE
    variables = {"box", "tip", "ctrl", "goal_pos"}
    model = mujoco.MjModel.from_xml_string(PUSHER_BOX)
    K = args.samples
    program = CostProgram.compile(source, variables)
    cost_s = {"native": [], "sandbox": []}

    def env(batch):  # noqa: ANN001, ANN202 - a RolloutBatch
        return {"box": batch.sensor("box_pos"), "tip": batch.sensor("tip_pos"), "ctrl": batch.controls,
                "goal_pos": GOAL}

    def timed(kind: str):  # noqa: ANN202
        def cost(batch):  # noqa: ANN001, ANN202
            e = env(batch)
            t0 = time.perf_counter()
            out = native(e["box"], e["tip"], e["ctrl"]) if kind == "native" else program.costs("push", e, K)[0]
            cost_s[kind].append(time.perf_counter() - t0)
            return out
        return cost

    planners = {k: MPPI(model, MPPIConfig(samples=K, horizon_s=0.5, nthread=os.cpu_count()), timed(k))
                for k in cost_s}
    step_s = {k: [] for k in cost_s}
    t_probe = time.perf_counter()
    sample = {"box": np.zeros((K, 50, 3)), "tip": np.zeros((K, 50, 3)), "ctrl": np.zeros((K, 50, 2)), "goal_pos": GOAL}
    report = probe(source, variables, {"push": (K,)}, sample)
    t_probe = time.perf_counter() - t_probe
    for i in range(args.steps):
        for kind in (list(cost_s) if i % 2 == 0 else list(cost_s)[::-1]):
            d = mujoco.MjData(model)
            mujoco.mj_forward(model, d)
            planners[kind].step(d)
            step_s[kind].append(planners[kind].last.total_s)
    for p in planners.values():
        p.close()
    med = {k: float(np.median(v)) for k, v in step_s.items()}
    cmed = {k: float(np.median(v)) for k, v in cost_s.items()}
    share = cmed["sandbox"] / med["sandbox"]
    print(f"machine: {machine_info()}")
    print(f"K={K}, horizon 0.5 s, {args.steps} steps per variant, medians:")
    for k in cost_s:
        print(f"  {k:8s} MPPI step {med[k] * 1000:7.2f} ms   cost {cmed[k] * 1000:6.3f} ms")
    print(f"sandboxed cost = {share * 100:.2f} % of its MPPI iteration (target <= 10 %); "
          f"{cmed['sandbox'] / cmed['native']:.2f}x the hand-written numpy cost")
    print(f"probe (check + compile + child process + {len(report.seconds_per_call)} function): {t_probe * 1000:.0f} ms")
    figures = {} if args.no_payloads else payload_suite()
    print(json.dumps({**figures, "samples": K, "step_ms": med["sandbox"] * 1000, "cost_ms": cmed["sandbox"] * 1000,
                      "cost_share": share, "overhead_vs_numpy": cmed["sandbox"] / cmed["native"],
                      "probe_ms": t_probe * 1000}))


if __name__ == "__main__":
    main()
