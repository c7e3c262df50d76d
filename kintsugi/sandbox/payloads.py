"""Hostile and broken cost code, the suite the sandbox is held to (its tests and `bench/bench_sandbox.py`).

Payloads are grouped: imports, escapes through dunders and frames, dangerous builtins, huge
exponents and numbers, memory bombs, endless loops and recursion, wrong shapes, NaN, broken syntax
and forbidden statements. Every one must be refused with a clear SandboxError in bounded time, and
nothing may escape (a canary file that escaping code would write stays absent).

`IN_LOOP` are valid programs whose cost depends on the state: cheap on the probe's sample inputs,
runaway on the states a control loop meets (`LOOP_STATE`); the probe accepts them, and the loop's
bound (`kintsugi.sandbox.guard`) must stop every call of theirs within a second.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kintsugi.sandbox.probe import ProbeLimits

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

def _runaway(condition: str, params: str = "tcp", lines: int = 110) -> str:
    """A cost whose heavy branch (whole-array trigonometry, `lines` deep) runs only when `condition` holds."""
    heavy = "\n".join("    y = smoothstep(tan(arctan2(y, y)), y, y)" for _ in range(lines))
    return fn(f"y = tcp\nif {condition}:\n{heavy}\n    return mean(norm(y), axis=-1)\nreturn mean(norm(tcp), axis=-1)",
              params)


IN_LOOP = [
    _runaway("max(tcp) > 0.9"),  # the probe's tool stays within 0.1..0.3 m; the loop's reaches 1 m
    _runaway("min(force) < -1.0", "tcp, force", 100),
    _runaway("mean(action) > 0.5", "tcp, action", 105),
    _runaway("tcp[0, 0, 2] > 0.5 and min(force) < 0", "tcp, force", 100),
]
"""Pass the probe (a few microseconds there), run for seconds per call on `LOOP_STATE`."""
LOOP_STATE = {"tcp": np.full((256, 50, 3), 1.0), "target": ENV["target"], "action": np.full((256, 50, 4), 0.9),
              "force": np.full((256, 50), -3.0)}
LOOP_K = 256
