"""The toy plugins through the command line: `--plugin` on every command that resolves names, a plugin
task run by a built-in method and by a plugin method with typed settings, and a campaign whose worker
processes import the plugins themselves (PYTHONPATH holds the repo root, as a user's would)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from kintsugi.cli import app

ROOT = Path(__file__).resolve().parents[2]
TABLETOP = ("--plugin", "tests.plugins.toy_tabletop")
METHOD = ("--plugin", "tests.plugins.toy_method")


def invoke(*args: object):  # noqa: ANN201
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert "Traceback" not in result.output, result.output
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit), result.exception
    return result


@pytest.mark.parametrize("args", [
    ("run", "toy-lift-block"), ("bench", "toy-lift-block"), ("report", "runs/nowhere"), ("tasks",), ("methods",),
    ("reasoners",), ("graph", "toy-lift-block"), ("export", "runs/nowhere", "--format", "hdf5", "--out", "x"),
])
def test_every_command_that_resolves_names_takes_plugins_first(args: tuple[str, ...]) -> None:
    res = invoke(*args, "--plugin", "kintsugi_nowhere")
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert lines == ["error: plugin module 'kintsugi_nowhere' not found; it must be importable "
                     "(on PYTHONPATH or installed)"], res.stderr


def test_listings_show_the_plugins_entries() -> None:
    res = invoke("tasks", "--plugin", "tests.plugins.toy_contact", *TABLETOP)
    assert res.exit_code == 0 and "toy-raise-cube" in res.output and "toy-lift-block" in res.output
    assert "pick-box" in res.output  # the built-ins stay
    res = invoke("methods", *METHOD)
    assert res.exit_code == 0 and "toy-first-actions" in res.output and "scripted" in res.output


def test_run_a_plugin_task_with_a_builtin_method(tmp_path: Path) -> None:
    path = tmp_path / "lift.json"
    res = invoke("run", "toy-lift-block", *TABLETOP, "--method", "scripted", "--condition", "pose", "--seed", "3",
                 "--record", path)
    assert res.exit_code == 0, res.output
    record = json.loads(path.read_text())
    assert record["success"] and record["error"] is None and record["physics_steps"] > 0
    assert record["task_figures"]["held_left"] and record["task_figures"]["rise_m"] > 0.06


def test_run_a_plugin_method_with_its_typed_settings(tmp_path: Path) -> None:
    path = tmp_path / "first.json"
    res = invoke("run", "pour-single", *METHOD, "--method", "toy-first-actions", "--set", "method.max_actions=3",
                 "--record", path)
    assert res.exit_code == 0, res.output
    record = json.loads(path.read_text())
    assert record["method_figures"] == {"ran": 3, "reached": 3, "stopped_early": True}
    assert len(record["skills"]) == 3 and not record["framework_success"]  # it knows it stopped early
    res = invoke("run", "pour-single", *METHOD, "--method", "toy-first-actions", "--set", "method.max_action=3",
                 "--record", path)
    assert res.exit_code == 2
    assert res.stderr.strip() == ("error: unknown config key 'method.max_action': method has keys max_actions "
                                  "(the settings of method 'toy-first-actions')")


@pytest.mark.slow
def test_bench_imports_the_plugins_in_its_workers(tmp_path: Path) -> None:
    out = tmp_path / "campaign"
    env = os.environ | {"PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    cmd = [sys.executable, "-c", "from kintsugi.cli import app; app()", "bench", "toy-lift-block", *TABLETOP, *METHOD,
           "--methods", "scripted,toy-first-actions", "--conditions", "none", "--trials", "2", "--workers", "1",
           "--out", str(out)]  # toy-first-actions at its default, max_actions=1
    done = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    config = json.loads((out / "campaign.json").read_text())["config"]
    assert config["plugins"] == ["tests.plugins.toy_tabletop", "tests.plugins.toy_method"]
    records = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len(records) == 4 and all(r["error"] is None for r in records)
    by_method = {m: [r for r in records if r["method"] == m] for m in ("scripted", "toy-first-actions")}
    assert all(r["success"] for r in by_method["scripted"])
    assert all(r["method_figures"] == {"ran": 1, "reached": 1, "stopped_early": True}
               for r in by_method["toy-first-actions"])
    res = invoke("report", out, *TABLETOP)  # the campaign's own plugins are loaded from campaign.json too
    assert res.exit_code == 0, res.output
