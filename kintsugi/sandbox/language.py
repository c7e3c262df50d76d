"""The cost language: a small, vectorized subset of Python, checked on its syntax tree.

A cost program is a sequence of top-level functions. Each function's parameters are names of
variables the caller provides (numpy arrays over the K sampled rollouts, e.g. `tcp`, `action`);
its body assigns locals, branches with `if`/`else` or `a if c else b`, and returns an array.

    def reach(tcp, target):
        d = norm(tcp - target)
        return d ** 2 + 0.1 * where(d < 0.02, 0.0, 1.0)

Allowed: number constants, arithmetic, comparisons, `and`/`or`/`not`, the functions in
`FUNCTIONS` (and functions defined earlier in the same program: no recursion), subscripts with
constant indices and slices (`x[..., 2]`, `x[:, :-1]`), `if`/`else`, `a if c else b`, `return`.

Refused, each with the line and column: imports, attribute access (the route to `__class__`,
`__globals__`, `__subclasses__`), any name that is not a parameter, local, earlier function or
allowed function (so no `open`, `eval`, `exec`, `getattr`), loops and comprehensions, lambdas,
classes, strings, list/dict/set literals, `global`, `try`, `with`, `yield`, `await`, `del`,
exponents that are not small constants, and programs beyond the size limits. Why not
RestrictedPython: it guards a general Python; costs need no loops, strings or attributes, and
a whitelist of a dozen node types is both stricter and shorter than its guards.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass

from kintsugi.core.errors import SandboxError

MAX_SOURCE_CHARS = 20_000
MAX_NODES = 3_000
MAX_DEPTH = 60
"""Deeper expressions are refused before Python's own compiler would hit its recursion limit."""
MAX_CONSTANT = 1e9
MAX_EXPONENT = 16.0
MAX_INDEX = 1_000
REDUCTION_KEYWORDS = frozenset({"axis", "keepdims"})

FUNCTIONS: dict[str, str] = {
    "abs": "absolute value", "sqrt": "square root", "square": "x**2", "exp": "e**x", "log": "natural log",
    "sin": "sine", "cos": "cosine", "tan": "tangent", "arctan2": "arctan2(y, x)", "tanh": "tanh",
    "sign": "sign", "minimum": "elementwise minimum of two arrays", "maximum": "elementwise maximum",
    "clip": "clip(x, lo, hi)", "where": "where(condition, a, b)", "sum": "sum(x, axis=...)",
    "mean": "mean(x, axis=...)", "min": "min(x, axis=...) (a reduction)", "max": "max(x, axis=...)",
    "norm": "Euclidean norm over the last axis", "dot": "dot(a, b): sum of a*b over the last axis",
    "logical_and": "elementwise and", "logical_or": "elementwise or", "logical_not": "elementwise not",
    "relu": "maximum(x, 0)", "smoothstep": "smoothstep(x, lo, hi): 0 below lo, 1 above hi, smooth between",
}
"""Name -> what it does (the prompt lists these). Implementations: program.py."""
CONSTANTS: dict[str, float] = {"pi": 3.141592653589793, "e": 2.718281828459045, "inf": float("inf")}

_EXPR = (ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare, ast.IfExp, ast.Call, ast.Name, ast.Constant,
         ast.Subscript, ast.Load, ast.Store, ast.operator, ast.unaryop, ast.boolop, ast.cmpop, ast.keyword)
_STATEMENTS = (ast.Assign, ast.AugAssign, ast.If, ast.Return, ast.Pass, ast.Expr)
_OPERATORS = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.Mod, ast.FloorDiv, ast.USub, ast.UAdd, ast.Not,
              ast.And, ast.Or, ast.Eq, ast.NotEq, ast.Lt, ast.LtE, ast.Gt, ast.GtE)


@dataclass(frozen=True)
class Signature:
    """A checked function: its name and the variables it takes, in order."""

    name: str
    params: tuple[str, ...]


def _fail(node: ast.AST | None, what: str, kind: str = "forbidden") -> SandboxError:
    where = f"line {node.lineno}, column {node.col_offset + 1}: " if node is not None and hasattr(node, "lineno") \
        else ""
    return SandboxError(kind, f"cost code rejected: {where}{what}")


def parse(source: str) -> ast.Module:
    """Source -> syntax tree, with size limits and every parser failure as one SandboxError."""
    if not isinstance(source, str):
        raise SandboxError("syntax", f"cost code must be text, not {type(source).__name__}")
    if len(source) > MAX_SOURCE_CHARS:
        raise SandboxError("too-large", f"cost code rejected: {len(source)} characters, more than {MAX_SOURCE_CHARS}")
    try:
        tree = ast.parse(source, filename="<cost>", mode="exec")
    except SyntaxError as exc:
        raise SandboxError("syntax", f"cost code does not parse: line {exc.lineno}: {exc.msg}") from None
    except (ValueError, RecursionError, MemoryError) as exc:  # null bytes, absurd nesting
        raise SandboxError("syntax", f"cost code does not parse: {type(exc).__name__}: {exc}"[:300]) from None
    count = sum(1 for _ in ast.walk(tree))
    if count > MAX_NODES:
        raise SandboxError("too-large", f"cost code rejected: {count} syntax nodes, more than {MAX_NODES}")
    return tree


def check(tree: ast.Module, variables: set[str] | frozenset[str]) -> list[Signature]:
    """Every rule of the language, or a SandboxError naming the first broken one and where."""
    signatures: list[Signature] = []
    if not tree.body:
        raise _fail(None, "no function defined; define e.g. `def cost(tcp, action): return ...`", "syntax")
    for stmt in tree.body:
        if not isinstance(stmt, ast.FunctionDef):
            raise _fail(stmt, f"only function definitions may stand at the top level, not {_name(stmt)}")
        signatures.append(_check_function(stmt, variables, {s.name for s in signatures}))
    names = [s.name for s in signatures]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise _fail(None, f"function {dupes[0]!r} is defined twice")
    return signatures


def _name(node: ast.AST) -> str:
    return type(node).__name__


def _check_function(fn: ast.FunctionDef, variables: set[str] | frozenset[str], earlier: set[str]) -> Signature:
    if fn.decorator_list or fn.returns is not None or getattr(fn, "type_params", None):
        raise _fail(fn, f"function {fn.name!r}: decorators, annotations and type parameters are not allowed")
    _check_identifier(fn, fn.name)
    if fn.name in FUNCTIONS or fn.name in CONSTANTS:
        raise _fail(fn, f"function {fn.name!r} would hide the built-in function or constant of that name")
    a = fn.args
    if a.posonlyargs or a.vararg or a.kwonlyargs or a.kwarg or a.defaults or a.kw_defaults:
        raise _fail(fn, f"function {fn.name!r}: only plain parameters (no defaults, *args, **kwargs)")
    params = tuple(arg.arg for arg in a.args)
    for arg in a.args:
        if arg.annotation is not None:
            raise _fail(arg, "parameter annotations are not allowed")
        if arg.arg not in variables:
            raise _fail(arg, f"function {fn.name!r}: unknown variable {arg.arg!r}; parameters must be among: "
                             f"{', '.join(sorted(variables))}")
    if len(set(params)) != len(params):
        raise _fail(fn, f"function {fn.name!r}: a parameter is repeated")
    scope = set(params)
    body = fn.body[1:] if _is_docstring(fn.body[0]) else fn.body
    for stmt in body:
        _check_statement(stmt, scope, earlier)
    if not any(isinstance(n, ast.Return) for n in ast.walk(fn)):
        raise _fail(fn, f"function {fn.name!r} never returns a value")
    return Signature(fn.name, params)


def _is_docstring(stmt: ast.stmt) -> bool:
    return isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant) and isinstance(stmt.value.value, str)


def _check_identifier(node: ast.AST, name: str) -> None:
    if name.startswith("_"):
        raise _fail(node, f"names may not start with an underscore ({name!r})")


def _check_statement(stmt: ast.stmt, scope: set[str], functions: set[str]) -> None:
    if not isinstance(stmt, _STATEMENTS):
        raise _fail(stmt, f"{_name(stmt)} statements are not allowed (no imports, loops, classes, try, with, "
                          f"global, del); use assignments, if/else and return")
    if isinstance(stmt, ast.Assign):
        if len(stmt.targets) != 1 or not isinstance(stmt.targets[0], ast.Name):
            raise _fail(stmt, "assign to one plain name at a time (no tuple unpacking, subscripts or attributes)")
        _check_expr(stmt.value, scope, functions)
        _bind(stmt.targets[0], scope, functions)
    elif isinstance(stmt, ast.AugAssign):
        if not isinstance(stmt.target, ast.Name) or stmt.target.id not in scope:
            raise _fail(stmt, "augmented assignment needs a local name assigned before")
        _check_operator(stmt, stmt.op, stmt.value)
        _check_expr(stmt.value, scope, functions)
    elif isinstance(stmt, ast.If):
        _check_expr(stmt.test, scope, functions)
        # Names bound in either branch are known after it (Python's rule); an unbound one fails at run time.
        for body in (stmt.body, stmt.orelse):
            for s in body:
                _check_statement(s, scope, functions)
    elif isinstance(stmt, ast.Return):
        if stmt.value is None:
            raise _fail(stmt, "return a value")
        _check_expr(stmt.value, scope, functions)
    elif isinstance(stmt, ast.Expr):
        raise _fail(stmt, "an expression on its own line does nothing; assign it or return it")


def _bind(target: ast.Name, scope: set[str], functions: set[str]) -> None:
    _check_identifier(target, target.id)
    if target.id in FUNCTIONS or target.id in CONSTANTS or target.id in functions:
        raise _fail(target, f"{target.id!r} is a function or constant; choose another local name")
    scope.add(target.id)


def _check_expr(node: ast.expr, scope: set[str], functions: set[str], depth: int = 0) -> None:
    if depth > MAX_DEPTH:
        raise _fail(node, f"expression nested deeper than {MAX_DEPTH} levels", "too-large")
    if not isinstance(node, _EXPR):
        raise _fail(node, _refusal(node))
    nxt = depth + 1
    if isinstance(node, ast.Constant):
        _check_constant(node)
    elif isinstance(node, ast.Name):
        _check_identifier(node, node.id)
        if node.id not in scope and node.id not in CONSTANTS:
            hint = " (it is a function: call it)" if node.id in FUNCTIONS or node.id in functions else ""
            raise _fail(node, f"unknown name {node.id!r}{hint}; known here: "
                              f"{', '.join(sorted(scope | set(CONSTANTS)))}")
    elif isinstance(node, ast.BinOp):
        _check_operator(node, node.op, node.right)
        _check_expr(node.left, scope, functions, nxt)
        _check_expr(node.right, scope, functions, nxt)
    elif isinstance(node, ast.UnaryOp):
        _check_operator(node, node.op, None)
        _check_expr(node.operand, scope, functions, nxt)
    elif isinstance(node, ast.BoolOp):
        _check_operator(node, node.op, None)
        for v in node.values:
            _check_expr(v, scope, functions, nxt)
    elif isinstance(node, ast.Compare):
        for op in node.ops:
            _check_operator(node, op, None)
        for v in (node.left, *node.comparators):
            _check_expr(v, scope, functions, nxt)
    elif isinstance(node, ast.IfExp):
        for v in (node.test, node.body, node.orelse):
            _check_expr(v, scope, functions, nxt)
    elif isinstance(node, ast.Call):
        _check_call(node, scope, functions, nxt)
    elif isinstance(node, ast.Subscript):
        _check_expr(node.value, scope, functions, nxt)
        _check_index(node.slice)
    else:  # keyword, operator and context nodes are reached through their parents only
        raise _fail(node, _refusal(node))


def _refusal(node: ast.AST) -> str:
    if isinstance(node, ast.Attribute):
        return f"attribute access ('.{node.attr}') is not allowed; use the functions: {', '.join(FUNCTIONS)}"
    if isinstance(node, (ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)):
        return "comprehensions are not allowed; costs are vectorized: operate on whole arrays"
    if isinstance(node, ast.Lambda):
        return "lambdas are not allowed; define a top-level function"
    if isinstance(node, (ast.JoinedStr, ast.FormattedValue)):
        return "strings are not allowed"
    if isinstance(node, (ast.List, ast.Tuple, ast.Dict, ast.Set, ast.Starred)):
        return f"{_name(node)} literals are not allowed (only inside a subscript, e.g. x[..., 0:2])"
    return f"{_name(node)} is not allowed in cost code"


def _check_constant(node: ast.Constant) -> None:
    v = node.value
    if isinstance(v, bool) or v is None:
        return
    if isinstance(v, (int, float)):
        if abs(v) > MAX_CONSTANT:
            raise _fail(node, f"constant {v!r} is larger than {MAX_CONSTANT:g} in size; rescale the cost")
        return
    raise _fail(node, f"{type(v).__name__} constants are not allowed (only numbers, True, False, None)")


def _check_operator(node: ast.AST, op: ast.AST, right: ast.expr | None) -> None:
    if not isinstance(op, _OPERATORS):
        raise _fail(node, f"operator {_name(op)} is not allowed (no bitwise or matrix operators)")
    if isinstance(op, ast.Pow):
        value = _constant_number(right)
        if value is None or abs(value) > MAX_EXPONENT:
            raise _fail(node, f"exponents must be number constants within +-{MAX_EXPONENT:g} (e.g. x ** 2); "
                              f"use exp/log for others")


def _constant_number(node: ast.expr | None) -> float | None:
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _constant_number(node.operand)
        return None if inner is None else (-inner if isinstance(node.op, ast.USub) else inner)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return float(node.value)
    return None


def _check_call(node: ast.Call, scope: set[str], functions: set[str], depth: int) -> None:
    if not isinstance(node.func, ast.Name):
        raise _fail(node, _refusal(node.func) if isinstance(node.func, ast.Attribute)
                    else "call functions by name only")
    name = node.func.id
    if name not in FUNCTIONS and name not in functions:
        known = ", ".join([*FUNCTIONS, *sorted(functions)])
        raise _fail(node, f"unknown function {name!r}; allowed: {known}")
    if len(node.args) > 4:
        raise _fail(node, f"{name}() takes at most 4 arguments here")
    for arg in node.args:
        if isinstance(arg, ast.Starred):
            raise _fail(arg, "*arguments are not allowed")
        _check_expr(arg, scope, functions, depth)
    for kw in node.keywords:
        if name in functions or kw.arg not in REDUCTION_KEYWORDS:
            raise _fail(node, f"keyword {kw.arg!r} is not allowed; only {', '.join(sorted(REDUCTION_KEYWORDS))} "
                              f"for reductions")
        value = _constant_number(kw.value) if kw.arg == "axis" else None
        if kw.arg == "axis" and (value is None or value != int(value) or abs(value) > 8):
            raise _fail(kw.value, "axis must be a small integer constant, e.g. axis=-1")
        if kw.arg == "keepdims" and not (isinstance(kw.value, ast.Constant) and isinstance(kw.value.value, bool)):
            raise _fail(kw.value, "keepdims must be True or False")


def _check_index(node: ast.expr) -> None:
    parts = node.elts if isinstance(node, ast.Tuple) else [node]
    if len(parts) > 6:
        raise _fail(node, "too many indices")
    for p in parts:
        if isinstance(p, ast.Slice):
            for bound in (p.lower, p.upper, p.step):
                if bound is not None:
                    _check_int_index(bound)
        elif isinstance(p, ast.Constant) and p.value is Ellipsis:
            continue
        else:
            _check_int_index(p)


def _check_int_index(node: ast.expr) -> None:
    value = _constant_number(node)
    if value is None or value != int(value) or abs(value) > MAX_INDEX or (
            isinstance(node, ast.Constant) and isinstance(node.value, float)):
        raise _fail(node, "indices must be integer constants, slices of them, or ... (e.g. x[..., 2], x[:, :-1])")
