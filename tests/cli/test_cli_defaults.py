"""What a user gets without naming everything: the task's own method and condition, printable settings."""

from __future__ import annotations

import json
from pathlib import Path

import yaml
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
    out = yaml.safe_load(res.output)
    assert out["methods"]["agentchord"]["max_actions"] == 7 and out["task"]["sim"]["timestep_s"] == 0.001
    as_json = runner.invoke(app, ["config", "pour-single", "--json", "--set", "methods.agentchord.max_actions=7",
                                  "--set", "sim.timestep_s=0.001"])
    assert json.loads(as_json.output) == out  # without --method: the task's own method, agentchord


def test_a_printed_config_read_back_gives_the_same_settings_for_every_task_and_method() -> None:
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import METHODS, TASKS
    from kintsugi.core.resolve import flatten_settings, settings_document

    load_builtins()
    own = lambda reg: [e for e in reg if e.factory.__module__.startswith("kintsugi.")]  # noqa: E731 - not plugins
    pairs = [(t.name, m.name) for t in own(TASKS) for m in own(METHODS) if t.factory().method_tag in m.tags]
    assert len(pairs) > 30
    for task, method in pairs:
        doc = settings_document(task, method, {})
        assert settings_document(task, method, flatten_settings(yaml.safe_load(yaml.safe_dump(doc)))) == doc


def test_config_file_sits_under_set_and_its_errors_are_one_line(tmp_path: Path) -> None:
    good = tmp_path / "s.yaml"
    good.write_text("task:\n  sim:\n    timestep_s: 0.001\nmethods:\n  agentchord:\n    max_actions: 9\n")
    res = runner.invoke(app, ["config", "pour-single", "--config", str(good), "--set", "sim.timestep_s=0.0005"])
    out = yaml.safe_load(res.output)
    assert out["task"]["sim"]["timestep_s"] == 0.0005 and out["methods"]["agentchord"]["max_actions"] == 9
    cases = {"task:\n  peg:\n    nope: 1\n": "peg.nope", "task: [\n": "not valid YAML at line",
             "tasks:\n  peg: {}\n": "unknown section 'tasks'", "task: 3\n": "must be a mapping",
             "task:\n  peg:\n    clearance_mm: wide\n": "peg.clearance_mm"}
    for i, (text, expected) in enumerate(cases.items()):
        bad = tmp_path / f"bad{i}.yaml"
        bad.write_text(text)
        for command in (["run", "peg-insertion"], ["bench", "peg-insertion", "--out", str(tmp_path / "c")]):
            res = runner.invoke(app, [*command, "--config", str(bad)])
            assert res.exit_code == 2 and expected in res.output, (text, res.output)
            assert "Traceback" not in res.output
    assert not (tmp_path / "c").exists()
    res = runner.invoke(app, ["run", "peg-insertion", "--config", str(tmp_path / "missing.yaml")])
    assert res.exit_code == 2 and "cannot read the settings file" in res.output


def test_record_names_say_the_reasoner_only_when_it_was_asked(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.chdir(tmp_path)
    res = runner.invoke(app, ["run", "peg-insertion", "--method", "baseline", "--seed", "1"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "runs" / "peg-insertion__baseline__round__none__1.json").exists()
    runner.invoke(app, ["run", "peg-insertion", "--method", "baseline", "--seed", "1", "--set", "peg.friction=0.4"])
    names = sorted(p.name for p in (tmp_path / "runs").iterdir())
    assert len(names) == 2 and names[1].startswith("peg-insertion__baseline__round__none__1__set-"), names


def test_config_names_a_bad_key() -> None:
    res = runner.invoke(app, ["config", "flip-box", "--method", "coral", "--set", "method.nope=1"])
    assert res.exit_code == 2 and "method.nope" in res.output and "coral" in res.output
