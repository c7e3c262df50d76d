"""The guides' code runs as written: each guide's Python block is saved as the module its text names,
loaded as a plugin, and the guide's `kintsugi run` commands are run against it."""

from __future__ import annotations

import json
import re
import shlex
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from kintsugi.cli import app

ROOT = Path(__file__).resolve().parents[2]


def blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


def commands(text: str, program: str = ".venv/bin/kintsugi") -> list[list[str]]:
    """Each shell command of the guide's bash blocks that calls `program`, as argv (comments dropped)."""
    out = []
    for block in blocks(text, "bash"):
        for line in block.replace("\\\n", " ").splitlines():
            argv = shlex.split(line, comments=True)
            if argv and argv[0] == program:
                out.append(argv[1:])
    return out


def _install(guide: str, module: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    text = (ROOT / "docs" / guide).read_text()
    (code,) = blocks(text, "python")
    (tmp_path / f"{module}.py").write_text(code)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.chdir(tmp_path)
    return text


@pytest.mark.slow
def test_add_a_method_guide_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = _install("add-a-method.md", "retry_insert", tmp_path, monkeypatch)
    runs = [c for c in commands(text) if c[0] == "run"]
    assert runs and any(c[0] == "bench" for c in commands(text))
    for argv in runs:
        res = CliRunner().invoke(app, [*argv, "--record", str(tmp_path / "r.json")])
        assert res.exit_code in (0, 1), res.output  # 1: the trial failed, which is recorded
        rec = json.loads((tmp_path / "r.json").read_text())
        assert rec["method"] == "retry-insert" and not rec["error"], rec["error"]
        assert "retries_used" in json.dumps(rec["method_figures"])
    bad = CliRunner().invoke(app, [*runs[0], "--set", "methods.retry-insert.retries=30"])
    assert bad.exit_code == 2 and "less than or equal to 10" in bad.output
    sys.modules.pop("retry_insert", None)


@pytest.mark.slow
def test_add_a_reasoner_backend_guide_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = _install("add-a-reasoner-backend.md", "declining", tmp_path, monkeypatch)
    runs = commands(text)
    assert len(runs) == 2
    records = []
    for i, argv in enumerate(runs):
        path = tmp_path / f"r{i}.json"
        res = CliRunner().invoke(app, [*argv, "--record", str(path)])
        assert "Traceback" not in res.output and path.exists(), res.output
        records.append(json.loads(path.read_text()))
    assert {c["backend"] for c in records[0]["transcript"]} == {"declining"}
    assert not any(c["error"] for c in records[0]["transcript"])
    declined = [c for c in records[1]["transcript"] if c["error"]]
    assert declined and all(c["role"] == "plan" for c in declined)
    bad = CliRunner().invoke(app, [*runs[0], "--set", "reasoner.options.nope=1"])
    assert bad.exit_code == 2 and "decline" in bad.output
    sys.modules.pop("declining", None)


def test_every_guide_the_readme_links_exists() -> None:
    readme = (ROOT / "README.md").read_text()
    links = re.findall(r"\]\(((?:docs/)[^)#]+)\)", readme)
    assert len(links) >= 10
    missing = [link for link in links if not (ROOT / link).exists()]
    owned_elsewhere = {"docs/add-a-task.md"}  # written with the task API
    assert not [m for m in missing if m not in owned_elsewhere], missing
    assert len(readme.splitlines()) <= 250
