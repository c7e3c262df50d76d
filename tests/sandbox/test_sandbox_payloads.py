"""Hostile and broken cost code: every payload is refused with a clear SandboxError, in bounded time, and
nothing escapes (a canary file that escaping code would write stays absent).

The payloads are `kintsugi.sandbox.payloads` (the bench runs the same suite). Most are refused by the
syntax check (no process); those that only fail when run go through the limited child process.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from kintsugi.core.errors import SandboxError
from kintsugi.sandbox import ProbeLimits, probe
from kintsugi.sandbox.payloads import CANARY, ENV, K, KINDS, LIMITS, PAYLOADS, fn



def test_there_are_at_least_200_distinct_payloads() -> None:
    assert len(set(PAYLOADS)) == len(PAYLOADS) >= 200


@pytest.mark.parametrize("source", PAYLOADS, ids=range(len(PAYLOADS)))
def test_payload_is_refused_clearly_in_bounded_time(source: str) -> None:
    CANARY.unlink(missing_ok=True)
    t0 = time.perf_counter()
    with pytest.raises(SandboxError) as exc:
        probe(source, set(ENV), {"cost": (K,)}, ENV, LIMITS)
    elapsed = time.perf_counter() - t0
    assert exc.value.kind in KINDS
    message = str(exc.value)
    assert 10 < len(message) < 800 and "Traceback" not in message
    assert elapsed < LIMITS.wall_s + 2.0
    assert not CANARY.exists()


def test_a_realistic_staged_cost_is_accepted_and_matches_numpy() -> None:
    source = '''
def reach(tcp, target):
    """Distance from the tool to the target, per step."""
    return norm(tcp - target)

def cost(tcp, target, action):
    d = reach(tcp, target)
    effort = sum(action ** 2, axis=-1)
    near = smoothstep(d, 0.02, 0.1)
    if 1 > 0:
        d = d + 0.0
    return mean(d + 0.01 * effort * near, axis=-1) + 10 * d[:, -1]

def done(tcp, target):
    return min(reach(tcp, target), axis=-1) < 0.05
'''
    report = probe(source, set(ENV), {"cost": (K,), "done": (K,)}, ENV, LIMITS)
    assert set(report.seconds_per_call) == {"cost", "done"}
    from kintsugi.sandbox import CostProgram

    got = CostProgram.compile(source, set(ENV)).call("cost", ENV, (K,))
    d = np.linalg.norm(ENV["tcp"] - ENV["target"], axis=-1)
    t = np.clip((d - 0.02) / 0.08, 0, 1)
    want = np.mean(d + 0.01 * np.sum(ENV["action"] ** 2, axis=-1) * t * t * (3 - 2 * t), axis=-1) + 10 * d[:, -1]
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_errors_say_where_and_what_to_write_instead() -> None:
    with pytest.raises(SandboxError, match=r"line 3, column 12: attribute access \('\.__class__'\)"):
        probe("def cost(tcp):\n    x = 1\n    return tcp.__class__", set(ENV), {"cost": (K,)}, ENV, LIMITS)
    with pytest.raises(SandboxError, match="unknown variable 'secret'; parameters must be among: action, force"):
        probe("def cost(secret):\n    return secret", set(ENV), {"cost": (K,)}, ENV, LIMITS)
    with pytest.raises(SandboxError, match=r"returned shape \(64, 10\).*expected \(64,\)"):
        probe(fn("return norm(tcp)"), set(ENV), {"cost": (K,)}, ENV, LIMITS)
    with pytest.raises(SandboxError, match="defines no function 'stage2'; it defines: cost"):
        probe(fn("return 1"), set(ENV), {"stage2": (K,)}, ENV, LIMITS)


def test_a_slow_cost_is_refused_for_the_loop() -> None:
    heavy = fn("x = tcp\n" + "\n".join("x = sqrt(x * x + 1e-3)" for _ in range(60)) + "\nreturn mean(norm(x), axis=-1)")
    big = {**ENV, "tcp": np.ones((4096, 50, 3))}
    with pytest.raises(SandboxError) as exc:
        probe(heavy, set(big), {"cost": (4096,)}, big, ProbeLimits(max_call_s=0.001))
    assert exc.value.kind == "slow" and "per call" in str(exc.value)


def test_memory_limit_stops_a_broadcast_bomb_in_the_child() -> None:
    """Valid code on inputs of valid shapes can still allocate N*N: the child's address-space limit stops it."""
    n = 20_000  # col * row would be 3.2 GB of float64
    env = {"col": np.ones((n, 1)), "row": np.ones((1, n))}
    with pytest.raises(SandboxError) as exc:
        probe("def cost(col, row):\n    return sum(col * row, axis=-1)", set(env), {"cost": (n,)}, env, LIMITS)
    assert exc.value.kind in {"memory", "runtime"} and ("memory" in str(exc.value) or "allocate" in str(exc.value))


def test_wall_clock_limit_kills_a_long_probe() -> None:
    env = {"grid": np.ones((2000, 2000))}
    slow = fn("x = grid\n" + "\n".join("x = sqrt(x * x + 1e-3)" for _ in range(60)) + "\nreturn sum(x, axis=-1)",
              "grid")
    t0 = time.perf_counter()
    with pytest.raises(SandboxError) as exc:
        probe(slow, set(env), {"cost": (2000,)}, env, ProbeLimits(wall_s=0.3))
    assert exc.value.kind == "timeout" and time.perf_counter() - t0 < 5.0  # a loaded machine starts a child slowly


def test_in_the_loop_non_finite_costs_become_infinite_and_are_counted() -> None:
    from kintsugi.sandbox import CostProgram

    program = CostProgram.compile(fn("return sqrt(mean(force, axis=-1) - 2.5)", "force"), set(ENV))
    costs, bad = program.costs("cost", ENV, K)
    assert costs.shape == (K,) and 0 < bad < K
    assert np.all(np.isposinf(costs[~np.isfinite(costs)])) and np.count_nonzero(np.isinf(costs)) == bad
