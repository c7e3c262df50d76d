"""Benchmarks use the product, not the test suite: no script under bench/ imports `tests` (what both need,
such as the requests of every role or the real-server harness, lives in `kintsugi.testing`)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_scan_sees_imports_of_tests() -> None:
    """Guard against a vacuous pass: module-level and lazy imports of `tests` count, other names do not."""
    source = ("import tests.x\nfrom tests import y\ndef f():\n    from tests.z import w\n"
              "import testsuite\nfrom kintsugi import tests\n")
    assert imports_of_tests(ast.parse(source)) == [1, 2, 4]


def imports_of_tests(tree: ast.AST) -> list[int]:
    """Line numbers of every `import tests...` and `from tests... import` (absolute imports) in `tree`."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "tests" for a in node.names):
            lines.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "tests":
            lines.append(node.lineno)
    return sorted(lines)


def test_no_bench_script_imports_tests() -> None:
    scripts = sorted((ROOT / "bench").rglob("*.py"))
    assert len(scripts) > 10 and ROOT / "bench" / "bench_reasoner_latency.py" in scripts
    found = [f"{path.relative_to(ROOT)}:{line}" for path in scripts
             for line in imports_of_tests(ast.parse(path.read_text(), filename=str(path)))]
    assert not found, ("bench/ imports the test suite; move what the benchmark and the tests share into the "
                       "product (kintsugi.testing):\n  " + "\n  ".join(found))
