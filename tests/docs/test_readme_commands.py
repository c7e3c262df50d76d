"""The README's and the guides' commands run as written: every `kintsugi` command line in a README or docs
shell block parses against the real command (names and options exist), the quick ones run, and the Python API
block runs."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import click
import pytest
import typer
from typer.testing import CliRunner

from kintsugi.cli import app

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text()
DOCS = sorted((ROOT / "docs").glob("*.md"))


def readme_commands(text: str = README) -> list[list[str]]:
    out = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            argv = shlex.split(line.replace("<record>", "record"), comments=True)
            if argv[:1] == [".venv/bin/kintsugi"]:
                out.append(argv[1:])
    return out


def docs_commands() -> list[list[str]]:
    return [argv for page in DOCS for argv in readme_commands(page.read_text())]


def test_every_readme_and_docs_command_parses() -> None:
    commands = readme_commands()
    assert len(commands) >= 12 and len(docs_commands()) >= 20
    commands += docs_commands()
    group = typer.main.get_command(app)
    for argv in commands:
        sub = group.get_command(click.Context(group), argv[0])
        assert sub is not None, argv
        args = argv[1:argv.index(">")] if ">" in argv else argv[1:]  # a shell redirect is not an argument
        sub.make_context(argv[0], args, resilient_parsing=False)  # raises on a bad option


def test_the_quick_readme_commands_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    for argv in readme_commands() + docs_commands():
        if argv[0] in ("tasks", "methods") or (argv[0] == "config" and ">" not in argv):
            res = runner.invoke(app, argv)
            assert res.exit_code == 0, (argv, res.output)
    res = runner.invoke(app, ["config", "peg-insertion", "--method", "recovery"])
    (tmp_path / "peg.yaml").write_text(res.output)
    res = runner.invoke(app, ["run", "peg-insertion", "--config", "peg.yaml", "--set", "peg.clearance_mm=1",
                              "--set", "method.max_step_mm=5", "--seed", "1"])
    assert res.exit_code in (0, 1) and "Traceback" not in res.output, res.output


@pytest.mark.slow
def test_the_readme_python_block_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (code,) = re.findall(r"```python\n(.*?)```", README, flags=re.S)
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)  # noqa: S102 - the README's own example
    assert scope["rec"].method == "agentchord" and scope["rec"].condition == "drop"
    assert len(scope["records"]) == 6 and (tmp_path / "runs" / "api-demo" / "report.html").exists()
