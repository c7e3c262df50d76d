"""The package's shape: no import cycles, no package importing a layer above it, no oversized module.

Every module of `kintsugi` is parsed with `ast`; every `import` and `from ... import` counts, at module level
or inside a function (a lazy import is still a dependency). `from pkg import name` depends on the submodule
`pkg.name` when there is one, else on `pkg` itself. Strings are not imports: core finds the built-in tasks
and methods by name (`kintsugi.core.plugins.BUILTIN_MODULES`, imported with `importlib.import_module`), which
is how the bottom layer reaches the top without depending on it.

Layers, bottom to top (a package may import its own layer and the ones below):
    core < control, perception, sandbox, taskgraph, reasoning < worlds < methods < campaign < export < cli
with `kintsugi/__init__.py` on top. Importing the root package itself (`from kintsugi import __version__`) is
no dependency on a layer as long as the root imports no module of the package (checked here): Python runs it
before any module inside it anyway.

`testing` (requests of every role, the real-server harness) sits beside `campaign`, and no module outside it
imports it. Its `tiny_gguf.py` is a script for the servers' tool venv: it alone imports `gguf`, which the
package does not depend on, and no module imports it.

An import under `if TYPE_CHECKING:` is a dependency for the layers, but no import cycle: it never runs (a
module annotating with the type of a module that imports it, as `taskgraph.validate` does `TaskGraph`).
"""

from __future__ import annotations

import ast
from functools import lru_cache
from itertools import islice
from pathlib import Path

import networkx as nx

import kintsugi

ROOT = Path(kintsugi.__file__).resolve().parent
PACKAGE = "kintsugi"
MAX_LINES = 400

LAYERS: dict[str, int] = {
    "core": 0,
    "control": 1, "perception": 1, "sandbox": 1, "taskgraph": 1, "reasoning": 1,
    "worlds": 2,
    "methods": 3,
    "campaign": 4, "testing": 4,
    "export": 5,
    "cli": 6,
    "gym": 7,
}
TOP = max(LAYERS.values()) + 1
"""The layer of `kintsugi/__init__.py` (and of any module directly under kintsugi/)."""


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@lru_cache(maxsize=1)
def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _resolve(importer: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute module a `from ... import` names (relative imports resolved against the importer)."""
    if not node.level:
        return node.module or ""
    base = importer.split(".")
    if not is_package:
        base.pop()
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


@lru_cache(maxsize=1)
def import_graph() -> nx.DiGraph:
    """module -> imported module, for every import between modules of the package; edges carry the line."""
    known = modules()
    graph = nx.DiGraph()
    graph.add_nodes_from(known)
    for name, path in known.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        type_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If) and _is_type_checking(block.test)
                     for stmt in block.body for n in ast.walk(stmt)}
        for node in ast.walk(tree):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(name, path.name == "__init__.py", node)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
            for target in targets:
                if target == PACKAGE or target.startswith(PACKAGE + "."):
                    # `import kintsugi.a.b` of a name that is no module (an attribute): its nearest module
                    while target not in known and "." in target:
                        target = target.rsplit(".", 1)[0]
                    if target == name:
                        continue
                    runtime = id(node) not in type_only
                    if not graph.has_edge(name, target):
                        graph.add_edge(name, target, line=node.lineno, runtime=runtime)
                    elif runtime and not graph.edges[name, target]["runtime"]:
                        graph.edges[name, target].update(line=node.lineno, runtime=True)
    return graph


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def layer_of(module: str) -> tuple[str, int]:
    parts = module.split(".")
    if len(parts) < 2 or parts[1] not in LAYERS:
        return PACKAGE, TOP
    return parts[1], LAYERS[parts[1]]


def where(importer: str, imported: str) -> str:
    path = modules()[importer].relative_to(ROOT.parent)
    return f"{path}:{import_graph().edges[importer, imported]['line']}: {importer} imports {imported}"


def test_the_parser_sees_the_package():
    """Guard against a vacuous pass: the graph holds every layer and imports that are known to exist."""
    graph = import_graph()
    assert {layer_of(m)[0] for m in graph} == {PACKAGE, *LAYERS}
    assert graph.has_edge("kintsugi.core.runner", "kintsugi.core.record")
    assert graph.has_edge("kintsugi.methods.coral.formulate", "kintsugi.methods.coral.costlib")  # inside a function
    assert not graph.edges["kintsugi.taskgraph.validate", "kintsugi.taskgraph.model"]["runtime"]  # TYPE_CHECKING
    assert graph.number_of_edges() > 200


def test_no_import_cycles():
    everything = import_graph()
    graph = everything.edge_subgraph([(a, b) for a, b, runtime in everything.edges(data="runtime") if runtime])
    cycles = sorted(islice(nx.simple_cycles(graph), 50), key=lambda c: (len(c), c))[:20]  # a tangle has many
    if cycles:
        lines = []
        for cycle in cycles:
            lines.append(" -> ".join([*cycle, cycle[0]]))
            lines += [f"    {where(a, b)}" for a, b in zip(cycle, [*cycle[1:], cycle[0]])]
        raise AssertionError(f"{len(cycles)} import cycle(s) between modules of kintsugi (shortest first):\n"
                             + "\n".join(lines))


def test_no_package_imports_a_layer_above_it():
    graph = import_graph()
    assert not [b for b in graph.successors(PACKAGE)], (
        "kintsugi/__init__.py imports modules of the package, so importing it (`from kintsugi import "
        f"__version__`) now depends on them: {', '.join(sorted(graph.successors(PACKAGE)))}")
    upward = [(a, b) for a, b in graph.edges if b != PACKAGE and layer_of(b)[1] > layer_of(a)[1]]
    if upward:
        levels = [sorted(k for k, v in LAYERS.items() if v == level) for level in range(TOP)]
        order = " < ".join(names[0] if len(names) == 1 else "{" + ", ".join(names) + "}" for names in levels)
        raise AssertionError(f"{len(upward)} import(s) of a higher layer (layers: {order} < kintsugi/__init__.py):\n"
                             + "\n".join(f"  {where(a, b)}" for a, b in sorted(upward)))


def test_no_module_over_the_size_limit():
    sizes = {name: len(path.read_text().splitlines()) for name, path in modules().items()}
    over = sorted((n, name) for name, n in sizes.items() if n > MAX_LINES)
    assert not over, (f"{len(over)} module(s) over {MAX_LINES} lines (split them along their seams, one concept "
                      "per module):\n" + "\n".join(f"  {modules()[name].relative_to(ROOT.parent)}: {n} lines"
                                                  for n, name in reversed(over)))


def test_nothing_outside_testing_imports_it():
    graph = import_graph()
    inside = f"{PACKAGE}.testing"
    into = [(a, b) for a, b in graph.edges if layer_of(b)[0] == "testing" and layer_of(a)[0] != "testing"]
    assert not into, (f"{inside} is for checking backends, methods and servers; the package itself must not "
                      "import it:\n" + "\n".join(f"  {where(a, b)}" for a, b in sorted(into)))
    script = f"{inside}.tiny_gguf"
    assert script in graph and not list(graph.predecessors(script)), (
        f"{script} is a script for the servers' tool venv (it imports gguf): "
        f"{', '.join(sorted(graph.predecessors(script)))} import(s) it")
    gguf = sorted(name for name, path in modules().items() if name != script and _imports(path, "gguf"))
    assert not gguf, f"the package does not depend on gguf (only {script}, a script, uses it): {', '.join(gguf)}"


def _imports(path: Path, top: str) -> bool:
    """Whether the module at `path` imports the top-level package `top` anywhere."""
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == top for a in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == top:
            return True
    return False
