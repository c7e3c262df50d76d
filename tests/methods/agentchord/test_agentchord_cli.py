"""`kintsugi graph <task>`: compiles the task's graph from its first observation, prints it, writes the picture
(and DOT/JSON on request); bad input is one line and a non-zero exit."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from kintsugi.cli import app
from kintsugi.taskgraph.model import TaskGraph


@pytest.mark.slow
def test_graph_prints_and_draws_the_compiled_graph(tmp_path: Path) -> None:
    png, dot, js = tmp_path / "g.png", tmp_path / "g.dot", tmp_path / "g.json"
    r = CliRunner().invoke(app, ["graph", "pour-single", "--out", str(png), "--dot", str(dot), "--json", str(js)])
    assert r.exit_code == 0, r.output
    assert "Eq. 8: 24 recovery branches kept, 0 dropped" in r.output and "s6_place" in r.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    assert 'style="rounded,dashed"' in dot.read_text() and "digraph" in dot.read_text()
    g = TaskGraph.from_json(js.read_text())
    assert g.goal == "s6_place" and sum(1 for e in g.edges if e.kind == "recovery") > 0


def test_graph_errors_are_one_line(tmp_path: Path) -> None:
    runner = CliRunner()
    for args, message in (
        (["graph", "peg-insertion", "--out", str(tmp_path / "a.png")], "graphs are compiled for the tabletop"),
        (["graph", "no-such-task"], "unknown task 'no-such-task'"),
        (["graph", "pour-single", "--out", str(tmp_path / "a.jpg")], "must end in .png"),
        (["graph", "pour-single", "--out", str(tmp_path / "a.png"), "--condition", "storm"], "unknown condition"),
    ):
        r = runner.invoke(app, args)
        assert r.exit_code == 2, (args, r.output)
        assert message in r.output and "Traceback" not in r.output, (args, r.output)
