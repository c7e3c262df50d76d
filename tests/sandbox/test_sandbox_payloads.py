"""Hostile and broken cost code: every payload is refused with a clear SandboxError, in bounded time, and
nothing escapes (a canary file that escaping code would write stays absent).

Payloads are grouped as the issue lists them: imports, escapes through dunders and frames, dangerous
builtins, huge exponents and numbers, memory bombs, endless loops and recursion, wrong shapes, NaN,
broken syntax and forbidden statements. Most are refused by the syntax check (no process); those
that only fail when run go through the limited child process.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from kintsugi.core.errors import SandboxError
from kintsugi.sandbox import ProbeLimits, probe

K, T = 64, 10
ENV = {"tcp": np.linspace(0.1, 0.3, K * T * 3).reshape(K, T, 3), "target": np.array([0.5, 0.0, 0.1]),
       "action": np.linspace(-1, 1, K * T * 4).reshape(K, T, 4), "force": np.linspace(0, 5, K * T).reshape(K, T)}
LIMITS = ProbeLimits(cpu_s=1.0, wall_s=6.0, memory_mb=256)
CANARY = Path("/tmp/kintsugi-sandbox-canary")
KINDS = {"forbidden", "syntax", "too-large", "shape", "non-finite", "runtime", "memory", "timeout", "killed",
         "missing", "slow"}


def fn(body: str, params: str = "tcp") -> str:
    """A one-function program whose body is `body` (lines joined with newlines)."""
    return f"def cost({params}):\n" + "\n".join("    " + line for line in body.split("\n"))


# --- the payloads ---------------------------------------------------------------------------------

IMPORTS = [
    "import os", "import sys as s", "from os import system", "from . import x", "import numpy",
    fn("import os\nreturn norm(tcp)"), fn("from subprocess import run\nreturn norm(tcp)"),
    fn("return __import__('os').system('touch /tmp/kintsugi-sandbox-canary')"),
    fn("x = __import__\nreturn norm(tcp)"), fn("return importlib(tcp)"),
]

DUNDERS = ["__class__", "__subclasses__", "__globals__", "__builtins__", "__dict__", "__mro__", "__bases__",
           "__code__", "__closure__", "__getattribute__", "__reduce__", "__init__", "__self__", "__module__",
           "gi_frame", "f_globals", "f_back", "mro", "tofile", "ctypes", "base", "T", "shape", "dump", "func_globals"]
ESCAPES = []
for _attr in DUNDERS:
    ESCAPES += [fn(f"return tcp.{_attr}"), fn(f"return (1).{_attr}"), fn(f"return norm.{_attr}(tcp)"),
                fn(f"x = cost.{_attr}\nreturn norm(tcp)")]
ESCAPES += [
    fn("return ().__class__.__bases__[0].__subclasses__()"),
    fn("return norm.__globals__['__builtins__']['open']('/etc/passwd')"),
    fn("return [c for c in ().__class__.__base__.__subclasses__() if c.__name__ == 'Popen'][0]"),
    fn("return __builtins__"), fn("return __loader__"), fn("return __spec__"), fn("return _"),
    fn("return __name__"), fn("x = _private\nreturn x"), fn("_x = 1\nreturn norm(tcp)"),
]

BUILTINS = ["open", "eval", "exec", "compile", "getattr", "setattr", "delattr", "globals", "locals", "vars",
            "breakpoint", "input", "print", "help", "exit", "quit", "type", "object", "dir", "id", "memoryview",
            "bytearray", "bytes", "super", "classmethod", "staticmethod", "property", "iter", "next", "range", "len",
            "list", "dict", "np", "numpy", "os", "sys", "zeros", "ones", "empty", "full", "tile", "repeat", "reshape",
            "arange", "linspace", "frombuffer", "fromfile", "load", "save", "einsum", "matmul"]
CALLS = [fn(f"return {name}(tcp)") for name in BUILTINS] + [fn(f"x = {name}\nreturn norm(tcp)") for name in BUILTINS]

NUMBERS = [
    fn("return norm(tcp) ** 1e9"), fn("return 2 ** 10 ** 10"), fn("return 10 ** (10 ** 10)"),
    fn("return 9 ** 9 ** 9"), fn("return norm(tcp) ** norm(tcp)"), fn("return norm(tcp) ** (2 + 1)"),
    fn("return 1e400 + norm(tcp)"), fn("return 10000000000 + norm(tcp)"), fn("return norm(tcp) * 1e10"),
    fn("return ((10 ** 9) ** 16) ** 16 + norm(tcp)"),  # parses; overflows at once when run
    fn("return exp(1000 + mean(norm(tcp), axis=-1))"),  # inf
    fn("return norm(tcp) ** -17"), fn("return norm(tcp) ** 16.5"),
]

MEMORY = [
    fn("return 'a' * 1000000000"), fn("return [0] * 1000000000"), fn("return (1,) * 1000000000"),
    fn("return norm(tcp[None, None] * tcp[:, :, None, None])"), fn("return bytearray(10 ** 10)"),
    fn("return list(range(10 ** 10))"), fn("return zeros(10 ** 9)"), fn("return {1: tcp}"), fn("return {tcp}"),
    fn("return f'{tcp}'"), fn("return b'x' * 100"), fn("return norm(tcp[..., None])"),
    fn("return norm(tcp[[0, 1]])"), fn("return norm(tcp[tcp > 0])"), fn("return norm(tcp[0.5])"),
    fn("return norm(tcp[True])"), fn("return norm(tcp[..., 100000])"),
]

LOOPS = [
    fn("while True:\n    pass\nreturn norm(tcp)"), fn("for i in range(10 ** 12):\n    pass\nreturn norm(tcp)"),
    fn("return cost(tcp)"), "def a(tcp):\n    return b(tcp)\ndef b(tcp):\n    return a(tcp)",
    fn("return sum([x for x in range(10 ** 10)])"), fn("return sum(x for x in tcp)"),
    fn("return (lambda f: f(f))(lambda f: f(f))"), fn("yield tcp"), "async def cost(tcp):\n    return tcp",
    fn("try:\n    return norm(tcp)\nfinally:\n    pass"), fn("with tcp:\n    return norm(tcp)"),
    fn("x = [i for i in range(3)]\nreturn norm(tcp)"), fn("return {i: i for i in range(3)}"),
    fn("return sum({i for i in range(3)})"),
]

SHAPES = [  # each is valid code that returns the wrong shape for a (K,) cost, or no array at all
    fn("return tcp"), fn("return norm(tcp)"), fn("return tcp[0]"), fn("return tcp[..., 0]"),
    fn("return where(tcp > 0)"), fn("return sum(tcp, axis=0)"), fn("return norm(tcp)[0]"),
    fn("return mean(tcp, axis=1)"), fn("return clip(tcp, 0, 1)"), fn("return action", "action"),
    fn("return force", "force"), fn("return force[:, :2]", "force"),
]

NANS = [
    fn("return sqrt(mean(norm(tcp), axis=-1) - 10)"), fn("return log(-1 + 0 * mean(norm(tcp), axis=-1))"),
    fn("return inf - inf + mean(norm(tcp), axis=-1)"), fn("return inf * 0 + mean(norm(tcp), axis=-1)"),
    fn("return mean(norm(tcp), axis=-1) / 0"), fn("return 0.0 / 0.0 + mean(norm(tcp), axis=-1)"),
    fn("return log(mean(norm(tcp), axis=-1) * 0)"), fn("return inf + mean(norm(tcp), axis=-1)"),
    fn("return arctan2(0, 0) * inf + mean(norm(tcp), axis=-1)"), fn("return None"),
    fn("return mean(force, axis=-1) / (mean(force, axis=-1) - mean(force, axis=-1))", "force"),
]

SYNTAX = [
    "", "   ", "def", "def cost(tcp):", "def cost(tcp):\n    return tcp +", "def cost(tcp)\n    return tcp",
    "def cost(tcp):\n  return (((tcp)", "\x00", "def cost(tcp):\n    return tcp\x00",
    fn("return " + "(" * 500 + "tcp" + ")" * 500), fn("return " + " + ".join(["tcp"] * 4000)),
    fn("return " + "-" * 200 + "mean(norm(tcp), axis=-1)"), "x" * 30_000, "def cost(tcp):\n\treturn tcp\n  x",
]

STATEMENTS = [
    "class A:\n    pass", fn("global x\nreturn norm(tcp)"), "def cost(tcp):\n    def inner():\n        return 1\n"
    "    return inner()", fn("del tcp\nreturn 1"), fn("assert False\nreturn tcp"), fn("raise ValueError()"),
    "@dec\ndef cost(tcp):\n    return tcp", "def cost(tcp=1):\n    return tcp", "def cost(*tcp):\n    return tcp",
    "def cost(**tcp):\n    return tcp", "def cost(tcp: int):\n    return tcp", "def cost(tcp) -> int:\n    return tcp",
    fn("return (x := norm(tcp))"), fn("return norm(*tcp)"), "def cost(secret):\n    return secret",
    "def cost(tcp):\n    return 1\ndef cost(tcp):\n    return 2", "def norm(tcp):\n    return tcp",
    fn("sum = 1\nreturn norm(tcp)"), fn("x += 1\nreturn norm(tcp)"), fn("a, b = tcp, tcp\nreturn norm(a)"),
    fn("tcp[0] = 1\nreturn norm(tcp)"), fn("tcp.x = 1\nreturn norm(tcp)"), fn("x = 1"),
    fn("return norm(tcp, out=tcp)"), fn("return sum(norm(tcp), axis=tcp)"),
    fn("return sum(norm(tcp), axis=1.5)"), fn("return sum(norm(tcp), keepdims=1)"),
    fn("return where(tcp, tcp, tcp, tcp, tcp)"), fn("return sum(**tcp)"), fn("return tcp @ tcp"),
    fn("return tcp | tcp"), fn("return tcp << 2"), fn("return ~tcp"), fn("return tcp is tcp"),
    fn("return tcp in tcp"), fn("norm(tcp)\nreturn 1"), fn("return"), fn("pass"),
    fn("return norm(tcp[a:b])"), fn("return norm(tcp[::tcp])"), "x = 1", "print('hi')",
    fn("match tcp:\n    case _:\n        return tcp"), fn("nonlocal tcp\nreturn tcp"),
    "def cost(tcp):\n    return helper(tcp)\ndef helper(tcp):\n    return norm(tcp)",
    fn("if tcp:\n    return 1\nreturn 2"),  # an array's truth value is ambiguous: refused when run
    fn("return mean(norm(tcp), axis=-1) if tcp else 1"),
]

PAYLOADS = IMPORTS + ESCAPES + CALLS + NUMBERS + MEMORY + LOOPS + SHAPES + NANS + SYNTAX + STATEMENTS


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
    assert exc.value.kind == "timeout" and time.perf_counter() - t0 < 3.0


def test_in_the_loop_non_finite_costs_become_infinite_and_are_counted() -> None:
    from kintsugi.sandbox import CostProgram

    program = CostProgram.compile(fn("return sqrt(mean(force, axis=-1) - 2.5)", "force"), set(ENV))
    costs, bad = program.costs("cost", ENV, K)
    assert costs.shape == (K,) and 0 < bad < K
    assert np.all(np.isposinf(costs[~np.isfinite(costs)])) and np.count_nonzero(np.isinf(costs)) == bad
