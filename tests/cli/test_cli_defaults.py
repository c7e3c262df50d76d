"""What a user gets without naming everything: the task's own method and condition, printable settings."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from kintsugi.cli import app

runner = CliRunner()


def test_run_takes_the_tasks_first_default_condition(tmp_path: Path) -> None:
    path = tmp_path / "r.json"
    res = runner.invoke(app, ["run", "flip-box", "--method", "expert-fsm", "--set", "control.episode_s=0.3",
                              "--set", "control.samples=8", "--record", str(path)])
    assert path.exists(), res.output
    assert json.loads(path.read_text())["condition"] == "all"  # as `kintsugi bench flip-box` runs it


def test_config_prints_the_task_and_method_settings_with_overrides() -> None:
    res = runner.invoke(app, ["config", "pour-single", "--method", "agentchord",
                              "--set", "methods.agentchord.max_actions=7", "--set", "sim.timestep_s=0.001"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["method"]["max_actions"] == 7 and out["task"]["sim"]["timestep_s"] == 0.001


def test_config_names_a_bad_key() -> None:
    res = runner.invoke(app, ["config", "flip-box", "--method", "coral", "--set", "method.nope=1"])
    assert res.exit_code == 2 and "method.nope" in res.output and "coral" in res.output
