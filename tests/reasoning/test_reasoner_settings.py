"""`--set reasoner.<key>=value`: the common fields on ReasonerSettings, a backend's own options checked by
its settings class, one-line errors naming the key; and a backend from a one-file plugin."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest
from typer.testing import CliRunner

from kintsugi.cli import app
from kintsugi.core.errors import ConfigError, UnknownNameError
from kintsugi.core.record import ReasonerSettings, TrialRecord, TrialSpec
from kintsugi.core.resolve import split_overrides
from kintsugi.reasoning import REASONERS, load_builtin_backends, reasoner_settings


def test_split_overrides_sends_reasoner_keys_to_the_reasoner() -> None:
    task, method, reasoner = split_overrides({"peg.clearance_mm": 1, "method.x": 2, "reasoner.model": "m",
                                              "reasoner.options.replies": "r.jsonl"})
    assert task == {"peg.clearance_mm": 1} and method == {"x": 2}
    assert reasoner == {"model": "m", "options.replies": "r.jsonl"}


def test_common_fields_and_backend_options_are_applied_and_checked() -> None:
    out = reasoner_settings(ReasonerSettings(), {"backend": "scripted", "timeout_s": 5, "options.replies": "r.jsonl"})
    assert (out.backend, out.timeout_s, out.options) == ("scripted", 5, {"replies": "r.jsonl"})
    out = reasoner_settings(out, {"options": {"function": "m:f", "replies": None}})
    assert out.options == {"replies": None, "function": "m:f"}


def test_an_unknown_option_is_one_line_naming_the_key() -> None:
    with pytest.raises(ConfigError) as err:
        reasoner_settings(ReasonerSettings(backend="scripted"), {"options.replys": "r.jsonl"})
    text = str(err.value)
    assert "reasoner.options.replys" in text and "replies, function" in text and "\n" not in text
    with pytest.raises(ConfigError, match="unknown key 'reasoner.options.replies' .*embedded backend's options: none"):
        reasoner_settings(ReasonerSettings(), {"options.replies": "r.jsonl"})
    with pytest.raises(ConfigError, match="reasoner.timeout_s"):
        reasoner_settings(ReasonerSettings(), {"timeout_s": "soon"})
    with pytest.raises(ConfigError, match="unknown config key 'reasoner.modle'"):
        reasoner_settings(ReasonerSettings(), {"modle": "m"})
    with pytest.raises(UnknownNameError, match="unknown reasoner 'scriptd'; known: .*scripted"):
        reasoner_settings(ReasonerSettings(), {"backend": "scriptd"})


def test_the_cli_takes_reasoner_options_and_names_a_bad_key(tmp_path: Path) -> None:
    runner = CliRunner()
    res = runner.invoke(app, ["run", "peg-insertion", "--method", "recovery", "--reasoner", "scripted",
                              "--set", "reasoner.options.replys=x.jsonl", "--record", str(tmp_path / "r.json")])
    assert res.exit_code == 2 and "reasoner.options.replys" in res.output + res.stderr
    replies = tmp_path / "replies.jsonl"
    replies.write_text("\n".join(json.dumps({"role": "judge", "reply": {"success": True, "explanation": "ok"}})
                                 for _ in range(3)))
    res = runner.invoke(app, ["run", "peg-insertion", "--method", "recovery", "--reasoner", "scripted",
                              "--set", f"reasoner.options.replies={replies}", "--record", str(tmp_path / "r.json")])
    assert res.exit_code == 0, res.output
    rec = TrialRecord.model_validate_json((tmp_path / "r.json").read_text())
    assert [(c["role"], c["backend"]) for c in rec.transcript] == [("judge", "scripted")] * 3


def test_a_backend_from_a_one_file_plugin(tmp_path: Path) -> None:
    from kintsugi.core.plugins import load_plugins

    load_plugins(["tests.plugins.toy_backend"])
    from tests.plugins.toy_backend import CALLS

    before = dict(CALLS)
    res = CliRunner().invoke(app, ["run", "peg-insertion", "--method", "recovery", "--shape", "square", "--condition",
                                   "all", "--seed", "1", "--reasoner", "toy", "--plugin", "tests.plugins.toy_backend",
                                   "--record", str(tmp_path / "r.json")])
    assert res.exit_code == 0, res.output
    rec = TrialRecord.model_validate_json((tmp_path / "r.json").read_text())
    counted = {k: v - before.get(k, 0) for k, v in CALLS.items() if v > before.get(k, 0)}
    assert rec.transcript and {c["backend"] for c in rec.transcript} == {"toy"}
    assert counted == dict(Counter(c["role"] for c in rec.transcript))
    load_builtin_backends()
    assert {"embedded", "scripted", "openai", "toy"} <= set(REASONERS.names())


def test_run_trial_applies_reasoner_overrides_from_the_spec(tmp_path: Path) -> None:
    from kintsugi.core.runner import run_trial

    replies = tmp_path / "replies.jsonl"
    replies.write_text('{"success": false, "explanation": "scripted no"}\n')
    rec = run_trial(TrialSpec(task="peg-insertion", method="recovery", variant="square", condition="none", seed=0,
                              overrides={"reasoner.backend": "scripted", "reasoner.options.replies": str(replies)}))
    assert rec.transcript[0]["reply"] == {"success": False, "explanation": "scripted no"}
    assert "ran out" in rec.transcript[1]["error"] and "ran out" in rec.error


def test_method_overrides_scope_to_one_method_with_methods_dot_name() -> None:
    from kintsugi.core.errors import ConfigError
    from kintsugi.core.resolve import check_scoped

    over = {"method.latency_model_s": 1.0, "methods.agentchord.max_actions": 3, "cup.x": 0.1}
    assert split_overrides(over, "agentchord")[1] == {"latency_model_s": 1.0, "max_actions": 3}
    assert split_overrides(over, "doremi")[1] == {"latency_model_s": 1.0}
    assert split_overrides(over)[0] == {"cup.x": 0.1}
    check_scoped(over, ["agentchord", "doremi"])
    check_scoped({"methods.rekep.max_actions": 3}, ["agentchord"])  # a suite may set a method the run leaves out
    with pytest.raises(ConfigError, match="names method 'agentchrod'"):
        check_scoped({"methods.agentchrod.max_actions": 3}, ["agentchord"])
