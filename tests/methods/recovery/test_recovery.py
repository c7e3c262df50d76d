"""Recovery method logic with scripted reasoners, and the embedded reasoner's honesty."""

from __future__ import annotations

import subprocess
import sys

import pytest

from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning import REASONERS
from kintsugi.reasoning.scripted import ScriptedReasoner
from kintsugi.methods.recovery.types import AnalyzeReply, JudgeReply, PlanReply, PlanStep, RelativeMotion
from kintsugi.core.plugins import load_builtins
from kintsugi.core.runner import run_trial
from kintsugi.methods.recovery.skill_log import PegFigures
from kintsugi.core.record import ReasonerSettings, TrialSpec

load_builtins()


class Scripted:
    """Verdicts and plans from a script, for logic tests (answered through the scripted backend)."""

    verdicts: list[bool] = []
    plan_reply: PlanReply | Exception = PlanReply(steps=[PlanStep(skill="fit", goal={"y": 0.0})])
    calls = 0

    @classmethod
    def reply(cls, role: str, req):  # noqa: ANN001, ANN206
        if role == "judge":
            ok = cls.verdicts[cls.calls] if cls.calls < len(cls.verdicts) else False
            cls.calls += 1
            return JudgeReply(success=ok, explanation="scripted")
        if role == "analyze":
            return AnalyzeReply(what_happened="x", why="y", how_to_recover="z", restart_from="fit",
                                motions=[RelativeMotion(skill="fit", axis="y", delta=1.0)])
        if isinstance(cls.plan_reply, Exception):
            raise cls.plan_reply
        return cls.plan_reply


def _scripted(settings, options):  # noqa: ANN001, ANN202
    Scripted.calls = 0
    return ScriptedReasoner(Scripted.reply)


if "scripted-test" not in REASONERS:
    REASONERS.register("scripted-test", "test double")(_scripted)


def _run(seed: int = 0, condition: str = "none", **overrides):  # noqa: ANN003, ANN202
    spec = TrialSpec(task="peg-insertion", method="recovery", variant="square", condition=condition, seed=seed,
                     overrides=overrides, reasoner=ReasonerSettings(backend="scripted-test"))
    return run_trial(spec)


def test_consecutive_failures_end_the_trial_as_timeout() -> None:
    Scripted.verdicts = []
    Scripted.plan_reply = PlanReply(steps=[PlanStep(skill="fit", goal={"y": 0.0})])
    rec = _run(**{"method.max_consecutive_failures": 4})
    assert not rec.framework_success
    assert any(e.kind == "timeout" and "4 consecutive" in e.detail for e in rec.events)
    assert rec.executions["fit"] == 4  # the first fit and three recoveries, all judged failed
    assert rec.transitions == [("fit", "fit")] * 3


def test_over_large_goal_update_is_clamped_to_max_step() -> None:
    Scripted.verdicts = [False, True, True, True]
    Scripted.plan_reply = PlanReply(steps=[PlanStep(skill="fit", goal={"y": 500.0})])
    rec = _run(**{"method.max_step_mm": 4.0})
    fits = [s for s in rec.skills if s.skill == "fit"]
    assert fits[1].goal["y"] == pytest.approx(fits[0].goal["y"] + 4.0)
    assert any(e.kind == "plan-clamped" for e in rec.events)
    assert rec.framework_success


def test_reasoning_error_is_recorded_not_raised() -> None:
    Scripted.verdicts = [False]
    Scripted.plan_reply = ReasoningError("model reply did not parse")
    rec = _run()
    assert rec.error is not None and "did not parse" in rec.error
    assert not rec.framework_success


def test_default_condition_recovery_succeeds_with_embedded_reasoner() -> None:
    spec = TrialSpec(task="peg-insertion", method="recovery", variant="round", condition="none", seed=0)
    rec = run_trial(spec)
    assert rec.success and rec.framework_success
    assert rec.reasoning_calls == 3  # one verdict per checked skill, no recovery needed
    assert [c["role"] for c in rec.transcript] == ["judge", "judge", "judge"]


def test_embedded_reasoner_recovers_a_displaced_hole() -> None:
    """Hole 18 mm right of where the goals were taught: baseline fails, recovery finds it."""
    overrides = {"hole.y_offset_mm": [18.0, 18.0], "grasp.angle_deg": [0.0, 0.0]}
    base = run_trial(TrialSpec(task="peg-insertion", method="baseline", variant="round", condition="pose",
                              seed=0, overrides=overrides))
    rec = run_trial(TrialSpec(task="peg-insertion", method="recovery", variant="round", condition="pose",
                             seed=0, overrides=overrides))
    assert not base.success
    assert rec.success and rec.framework_success
    assert sum(PegFigures.of(rec).extra_executions.values()) >= 1


def test_embedded_reasoner_never_imports_the_simulator() -> None:
    code = ("import sys, kintsugi.methods.recovery.roles; "
            "bad = [m for m in sys.modules if m == 'mujoco' or m.startswith('kintsugi.worlds') and m not in "
            "('kintsugi.worlds', 'kintsugi.worlds.peg', 'kintsugi.worlds.peg.description')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
