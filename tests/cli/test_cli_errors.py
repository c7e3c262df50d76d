"""Error paths of the command line: one clear line, a non-zero exit, no traceback, nothing lost.

Also: text that looks like Rich markup (`[/INST]`, `[bold]`, `[/x]`) in any printed field is
shown verbatim. Real trials are few and short (a baseline trial ~0.2 s, a scripted recovery ~1 s).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from kintsugi.cli import _record_path, app
from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.scripted import ScriptedReasoner
from kintsugi.methods.recovery.types import AnalyzeReply, JudgeReply, PlanReply, PlanStep, RelativeMotion
from kintsugi.core.record import ReasonerSettings, TrialRecord, TrialSpec

MARKUP = "[/INST] [bold]not bold[/x]"


class MarkupReasoner:
    """Replies full of markup-like text; the first judgement fails so analyze and plan run too.
    With `fail=True` the judge raises, as an unreachable endpoint does (answered through the scripted backend)."""

    def __init__(self, fail: bool = False) -> None:
        self.fail = fail
        self.judged = 0

    def __call__(self, role: str, req):  # noqa: ANN001, ANN204
        if role == "judge":
            if self.fail:
                raise ReasoningError(f"cannot reach http://127.0.0.1:9/v1 {MARKUP}")
            self.judged += 1
            return JudgeReply(success=self.judged > 1, explanation=f"judged {MARKUP}")
        if role == "analyze":
            return AnalyzeReply(what_happened=MARKUP, why=MARKUP, how_to_recover=MARKUP, restart_from="fit",
                                motions=[RelativeMotion(skill="fit", axis="y", delta=1.0)])
        return PlanReply(steps=[PlanStep(skill="fit", goal={"y": 400.0})])  # clamped: a plan-clamped event


for _name, _fail in (("markup-test", False), ("unreachable-test", True)):
    if _name not in REASONERS:
        REASONERS.register(_name, f"test double {MARKUP}")(
            lambda settings, options, f=_fail: ScriptedReasoner(MarkupReasoner(fail=f), where="markup"))


def invoke(*args: str):  # noqa: ANN201
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert "Traceback" not in result.output, result.output
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit), result.exception
    return result


# ----- run -------------------------------------------------------------------------------------

def test_run_prints_markup_like_replies_verbatim_and_saves_the_record(tmp_path: Path) -> None:
    rec = tmp_path / "r.json"
    res = invoke("run", "peg-insertion", "--method", "recovery", "--shape", "square", "--reasoner", "markup-test",
                 "--record", rec)
    assert res.exit_code == 0, res.output
    assert f"judged {MARKUP}" in res.output and f"analysis: {MARKUP}" in res.output
    assert "plan-clamped" in res.output
    saved = TrialRecord.model_validate_json(rec.read_text())
    assert any(MARKUP in json.dumps(c.get("reply")) for c in saved.transcript)


def test_run_exits_nonzero_on_a_recorded_error_and_still_saves_the_record(tmp_path: Path) -> None:
    rec = tmp_path / "sub" / "r.json"
    res = invoke("run", "peg-insertion", "--method", "recovery", "--reasoner", "unreachable-test", "--record", rec)
    assert res.exit_code == 1
    assert f"cannot reach http://127.0.0.1:9/v1 {MARKUP}" in res.stderr
    saved = TrialRecord.model_validate_json(rec.read_text())
    assert saved.error and "cannot reach" in saved.error


def test_run_markup_like_task_name_is_an_unknown_task() -> None:
    res = invoke("run", "peg[/x]")
    assert res.exit_code == 2
    assert res.stderr.strip().splitlines() == [res.stderr.strip()]  # one line, not wrapped at 80 columns
    assert "unknown task 'peg[/x]'" in res.stderr and "peg-insertion" in res.stderr


@pytest.mark.parametrize("args, message", [
    (["--shape", "hexagon"], "unknown peg shape 'hexagon'"),
    (["--condition", "[bold]windy"], "unknown condition for task 'peg-insertion': '[bold]windy'"),
    (["--method", "[/x]"], "unknown method '[/x]'"),
    (["--reasoner", "nope"], "unknown reasoner 'nope'"),
    (["--set", "peg.nope=1"], "unknown config key 'peg.nope'"),
    (["--video", "trial.avi"], "video path trial.avi must end in .mp4 or .gif"),
    (["--record", "trial.txt"], "record path trial.txt must end in .json"),
    (["--video", "{file}/v.mp4"], "is a file, not a directory"),
    (["--record", "{file}/r.json"], "is a file, not a directory"),
    (["--record", "{dir}"], "is a directory"),
])
def test_run_rejects_bad_input_before_the_trial(tmp_path: Path, args: list[str], message: str) -> None:
    (tmp_path / "file").write_text("x")
    (tmp_path / "dir.json").mkdir()
    args = [a.format(file=tmp_path / "file", dir=tmp_path / "dir.json") for a in args]
    res = invoke("run", "peg-insertion", "--record", tmp_path / "r.json", *args)
    assert res.exit_code == 2
    assert message in res.stderr
    assert "ground truth" not in res.output and not (tmp_path / "r.json").exists()  # no trial ran


def test_run_openai_without_key_or_base_url_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    res = invoke("run", "peg-insertion", "--reasoner", "openai")
    assert res.exit_code == 2 and "needs an API key" in res.stderr


def test_negative_seed_is_a_usage_error() -> None:
    res = invoke("run", "peg-insertion", "--seed", "-1")
    assert res.exit_code == 2 and "--seed" in res.output


@pytest.mark.slow
def test_default_record_path_names_the_reasoner(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    res = invoke("run", "peg-insertion", "--seed", "1")
    assert res.exit_code == 0, res.output
    assert (tmp_path / "runs" / "peg-insertion__recovery__round__none__1__embedded.json").exists()  # the default method
    spec = TrialSpec(task="t", method="m", variant="v", condition="c", seed=2,
                     reasoner=ReasonerSettings(backend="openai", model="qwen2.5vl:7b"))
    assert _record_path(spec) == Path("runs/t__m__v__c__2__openai-qwen2.5vl-7b.json")
    default_model = _record_path(spec.model_copy(update={"reasoner": ReasonerSettings(backend="openai")}))
    assert default_model.name.startswith("t__m__v__c__2__openai-") and default_model != _record_path(spec)
    a, b = (_record_path(spec.model_copy(update={"overrides": {"hole.friction_scale": [1, v]}})) for v in (3, 5))
    assert a != b and a.name.startswith("t__m__v__c__2__openai-qwen2.5vl-7b__set-")  # other --set, other file


def test_version() -> None:
    from importlib.metadata import version

    res = invoke("--version")
    assert res.exit_code == 0 and res.output.strip() == f"kintsugi {version('kintsugi')}"


# ----- bench -----------------------------------------------------------------------------------

@pytest.mark.parametrize("args, message", [
    (["--methods", "baseline,nope"], "unknown method 'nope'"),
    (["--shapes", "round,[/x]"], "unknown peg shape '[/x]'"),
    (["--conditions", "none,windy"], "unknown condition for task 'peg-insertion': 'windy'"),
    (["--reasoner", "nope"], "unknown reasoner 'nope'"),
    (["--reasoner", "openai"], "needs an API key"),
    (["--set", "hole.nope=1"], "unknown config key 'hole.nope'"),
    (["--executor", "ray"], "pip install 'kintsugi[ray]'"),  # unless Ray is installed (then skipped)
    (["--executor", "nope"], "unknown executor 'nope'"),
    (["--out", "{file}"], "exists and is not a directory"),
    (["--out", "{file}/sub"], "is a file, not a directory"),
    (["--trials", "0"], "--trials"),
    (["--trials", "-3"], "--trials"),
    (["--videos-per-cell", "-1"], "--videos-per-cell"),
    (["--base-seed", "-1"], "--base-seed"),
    (["--workers", "0"], "--workers"),
    (["--trial-timeout", "0"], "--trial-timeout"),
    (["--suite", "strech"], "unknown suite 'strech' for task 'peg-insertion'; known: stretch, stretch-paper"),
])
def test_bench_rejects_bad_input_before_the_first_trial(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                        args: list[str], message: str) -> None:
    if args == ["--executor", "ray"]:
        try:
            import ray  # noqa: F401

            pytest.skip("Ray is installed")
        except ImportError:
            pass
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    (tmp_path / "file").write_text("x")
    out = tmp_path / "out"
    args = [a.format(file=tmp_path / "file") for a in args]
    res = invoke("bench", "peg-insertion", "--trials", "1", "--out", out, *args)
    assert res.exit_code == 2
    assert message in res.output
    assert not (out / "results.jsonl").exists()


def test_bench_with_errored_trials_says_so_and_exits_nonzero(tmp_path: Path) -> None:
    out = tmp_path / "out"
    res = invoke("bench", "fake-coin", "--plugin", "tests.fake_tasks", "--methods", "plain",
                 "--shapes", "raises", "--conditions", "easy", "--trials", "2", "--executor", "inline", "--out", out)
    assert res.exit_code == 1
    # Not a terminal: one plain progress line per finished trial.
    assert "1/2 fake-coin/plain/raises/easy/0: failure" in res.stderr and "2/2 " in res.stderr
    assert ("error: 1 of 2 trials errored (they count as failures); first: fake-coin/plain/raises/easy/0: "
            "RuntimeError: fake failure on seed 0") in res.stderr
    assert len((out / "results.jsonl").read_text().splitlines()) == 2  # nothing lost
    assert "1 of 2 trials errored" in (out / "report.md").read_text()
    res = invoke("report", out)
    assert res.exit_code == 0 and "1 of 2 trials errored" in res.stderr


def test_bench_suite_fixes_the_campaign_and_options_go_on_top(tmp_path: Path) -> None:
    out = tmp_path / "out"
    res = invoke("bench", "peg-insertion", "--suite", "stretch", "--methods", "recovery", "--shapes", "square",
                 "--trials", "1", "--executor", "inline", "--set", "peg.clearance_mm=0.5", "--out", out)
    assert res.exit_code == 0, res.output
    cfg = json.loads((out / "campaign.json").read_text())["config"]
    assert cfg["methods"] == ["recovery"] and cfg["variants"] == ["square"] and cfg["conditions"] == ["all"]
    assert cfg["overrides"]["camera.side_view"] is True and cfg["overrides"]["peg.clearance_mm"] == 0.5
    assert "kintsugi bench peg-insertion --suite stretch-paper" in res.output


def test_bench_suite_of_a_task_without_suites(tmp_path: Path) -> None:
    res = invoke("bench", "fake-coin", "--plugin", "tests.fake_tasks", "--suite", "stretch", "--out", tmp_path)
    assert res.exit_code == 2 and "this task has no named suites" in res.output


# ----- trial log -----------------------------------------------------------------------------

def test_trial_log_lines_are_verbatim_unless_marked_up() -> None:
    from rich.console import Console

    from kintsugi.core.log import TrialLog

    console = Console(record=True, width=200)
    log = TrialLog(echo=console.print)
    log.say("verdict: [bold]kept[/bold] [red]as written")  # valid markup, still shown as written
    log.event(1.0, "plan-clamped", "[/INST] step [b]1[/b]")
    log.say("[bold]styled[/bold]", markup=True)
    assert console.export_text().splitlines() == [
        "verdict: [bold]kept[/bold] [red]as written", "  1.00s plan-clamped: [/INST] step [b]1[/b]", "styled"]


def test_task_defaults_come_from_the_task():
    """Without --method a task runs its system's own method (its `default_method`), not the reference one."""
    from kintsugi.campaign.plan import task_defaults

    assert task_defaults("peg-insertion") == ("recovery", "round", ("none", "friction", "pose", "all"))
    assert task_defaults("pour-single")[:2] == ("agentchord", "default")
    assert task_defaults("pick-box")[:2] == ("coral", "default")


@pytest.mark.parametrize("task, method", [("pour-single", "baseline"), ("peg-insertion", "scripted"),
                                          ("pick-box", "agentchord")])
def test_a_method_of_another_system_is_refused_before_the_trial(tmp_path, task, method):
    result = invoke("run", task, "--method", method, "--record", tmp_path / "r.json")
    assert result.exit_code == 2
    assert f"method {method!r} does not run task {task!r}" in result.output
    assert not (tmp_path / "r.json").exists()


def test_an_unknown_tabletop_variant_is_refused_before_the_trial(tmp_path):
    result = invoke("run", "pour-single", "--variant", "round", "--record", tmp_path / "r.json")
    assert result.exit_code == 2 and "unknown variant 'round' for pour-single" in result.output
    assert not (tmp_path / "r.json").exists()
