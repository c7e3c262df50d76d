"""A checked cost program, compiled once and called in the control loop.

The tree that passed `language.check` is compiled as is (plus one rewrite: integer
constants in arithmetic become floats, so `(10 ** 9) ** 16 ** ...` overflows at once
instead of building a huge integer). It runs with no builtins at all; its only callables
are the numpy-backed `FUNCTIONS` and its own earlier functions. Its time per call is
bounded by construction (no loops, recursion or comprehensions; a bounded number of
whole-array operations), and `probe.py` measures it before the loop ever sees it.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from kintsugi.core.errors import SandboxError
from kintsugi.sandbox.guard import LoopBound, bounded
from kintsugi.sandbox.language import CONSTANTS, FUNCTIONS, Signature, check, parse


def _norm(x: Any) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.sqrt(np.sum(x * x, axis=-1))


def _smoothstep(x: Any, lo: Any, hi: Any) -> np.ndarray:
    t = np.clip((np.asarray(x, dtype=float) - lo) / np.maximum(np.asarray(hi, dtype=float) - lo, 1e-12), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _reduction(fn: Callable[..., Any]) -> Callable[..., Any]:
    def reduce(x: Any, axis: int | None = None, keepdims: bool = False) -> Any:
        return fn(np.asarray(x, dtype=float), axis=axis, keepdims=keepdims)
    return reduce


IMPLEMENTATIONS: dict[str, Callable[..., Any]] = {
    "abs": np.abs, "sqrt": np.sqrt, "square": np.square, "exp": np.exp, "log": np.log, "sin": np.sin,
    "cos": np.cos, "tan": np.tan, "arctan2": np.arctan2, "tanh": np.tanh, "sign": np.sign,
    "minimum": np.minimum, "maximum": np.maximum, "clip": np.clip, "where": np.where,
    "sum": _reduction(np.sum), "mean": _reduction(np.mean), "min": _reduction(np.min), "max": _reduction(np.max),
    "norm": _norm, "dot": lambda a, b: np.sum(np.asarray(a, dtype=float) * b, axis=-1),
    "logical_and": np.logical_and, "logical_or": np.logical_or, "logical_not": np.logical_not,
    "relu": lambda x: np.maximum(x, 0.0), "smoothstep": _smoothstep,
}
assert IMPLEMENTATIONS.keys() == FUNCTIONS.keys(), "every documented function has an implementation"


class _FloatConstants(ast.NodeTransformer):
    """Integer constants -> floats, except indices and keyword values (axis=-1 stays an int)."""

    def visit_Subscript(self, node: ast.Subscript) -> ast.AST:
        node.value = self.visit(node.value)
        return node

    def visit_keyword(self, node: ast.keyword) -> ast.AST:
        return node

    def visit_Constant(self, node: ast.Constant) -> ast.AST:
        if isinstance(node.value, int) and not isinstance(node.value, bool):
            return ast.copy_location(ast.Constant(float(node.value)), node)
        return node


@dataclass
class CostProgram:
    """Checked, compiled cost code: call its functions with variables by name."""

    source: str
    variables: frozenset[str]
    signatures: dict[str, Signature]
    _functions: dict[str, Callable[..., Any]] = field(repr=False)
    probed_s: dict[str, float] = field(default_factory=dict)
    """Seconds per call of each function as the probe measured it (filled in by whoever probed it; the loop's
    bound, `guard.LoopBound`, compares each call against it)."""

    @classmethod
    def compile(cls, source: str, variables: set[str] | frozenset[str]) -> "CostProgram":
        """Check `source` against the language and the variables a caller offers; compile it once."""
        tree = parse(source)
        signatures = check(tree, frozenset(variables))
        tree = ast.fix_missing_locations(_FloatConstants().visit(tree))
        namespace: dict[str, Any] = {"__builtins__": {}, **IMPLEMENTATIONS, **CONSTANTS}
        try:
            exec(compile(tree, "<cost>", "exec"), namespace)  # noqa: S102 - a checked tree, no builtins
        except (RecursionError, MemoryError, ValueError) as exc:
            raise SandboxError("syntax", f"cost code does not compile: {type(exc).__name__}") from None
        functions = {s.name: namespace[s.name] for s in signatures}
        return cls(source=source, variables=frozenset(variables), signatures={s.name: s for s in signatures},
                   _functions=functions)

    def has(self, name: str) -> bool:
        return name in self.signatures

    def bounded_call(self, name: str, env: Mapping[str, Any], shape: tuple[int, ...] | None = None,
                     bound: LoopBound = LoopBound()) -> np.ndarray:
        """`call` under the control loop's bound: a call far slower than its probe or than the loop's budget
        raises SandboxError('overrun') instead of stalling the loop (see `guard`)."""
        probed = self.probed_s.get(name)
        return bounded(name, bound.limit(probed), probed, lambda: self.call(name, env, shape))

    def call(self, name: str, env: Mapping[str, Any], shape: tuple[int, ...] | None = None) -> np.ndarray:
        """Run function `name` with its parameters taken from `env`.

        The result must broadcast to `shape` (when given) and is returned as a float array of
        exactly that shape; NaN and +-inf are returned as they are (the caller decides: the
        control loop treats them as +inf cost, the probe rejects them).
        """
        sig = self.signatures.get(name)
        if sig is None:
            raise SandboxError("missing", f"cost code defines no function {name!r}; it defines: "
                                          f"{', '.join(self.signatures) or 'nothing'}")
        missing = [p for p in sig.params if p not in env]
        if missing:
            raise SandboxError("missing", f"{name}() needs variables the caller did not provide: {', '.join(missing)}")
        try:
            with np.errstate(all="ignore"):
                out = self._functions[name](*(env[p] for p in sig.params))
                arr = np.asarray(out, dtype=float)
        except SandboxError:
            raise
        except RecursionError:
            raise SandboxError("runtime", f"{name}() recursed too deeply") from None
        except MemoryError:
            raise SandboxError("memory", f"{name}() ran out of memory") from None
        except Exception as exc:  # noqa: BLE001 - any failure of model-written code is its own error
            raise SandboxError("runtime", f"{name}() failed: {type(exc).__name__}: {exc}"[:400]) from None
        if shape is None:
            return arr
        try:
            return np.broadcast_to(arr, shape).astype(float, copy=True)
        except ValueError:
            raise SandboxError("shape", f"{name}() returned shape {arr.shape}, which does not fit the expected "
                                        f"{shape}; reduce over the extra axes (e.g. sum(x, axis=-1))") from None

    def costs(self, name: str, env: Mapping[str, Any], samples: int) -> tuple[np.ndarray, int]:
        """(K,) costs for the control loop (a bounded call) and how many were not finite: those become +inf, so a
        sample the code cannot score gets no weight instead of poisoning the others (MPPI's rule for diverged
        rollouts)."""
        out = self.bounded_call(name, env, (samples,))
        bad = ~np.isfinite(out) | np.isnan(out)
        out[bad] = np.inf
        return out, int(np.count_nonzero(bad))
