"""System C's Table I from hand-made contact records with known numbers (figures through `CoralFigures`)."""

import pytest

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.core.record import TrialRecord
from kintsugi.methods.coral.figures import CoralFigures
from kintsugi.campaign.systems.contact import belief_error, summarize, table_i

CFG = CampaignConfig(task="flip-box", methods=["coral", "l2r", "expert"], variants=["default"],
                     conditions=["all"], trials=2)
TRUTH = {"box.mass_kg": 0.5, "box.friction": 0.4}


def attempt(mass: float, friction: float, code: float = 1.0, mppi: float = 20.0) -> dict:
    return {"attempt": 1, "beliefs_before": {"box": {"mass_kg": mass, "friction": friction}}, "source": "",
            "stages": [], "regions": [], "knobs": {}, "code_ms_per_step": code, "mppi_ms_per_step": mppi}


def rec(method: str, seed: int, success: bool, figures: CoralFigures | None, **kw) -> TrialRecord:
    return TrialRecord(key=f"flip-box/{method}/default/all/{seed}", task="flip-box", method=method,
                       variant="default", condition="all", seed=seed, success=success, framework_success=success,
                       params=TRUTH, method_figures=figures.model_dump() if figures else {}, **kw)


def records() -> list[TrialRecord]:
    return [
        # coral seed 0: two attempts, the first planned with a 100 % / 50 % wrong belief, the second 20 % / 0 %.
        rec("coral", 0, True, CoralFigures(variant="coral", plan_from="formulation",
                                           attempts=[attempt(1.0, 0.6), attempt(0.6, 0.4, code=3.0)])),
        # coral seed 1: recalled from memory, one attempt, 0 % / 25 %.
        rec("coral", 1, True, CoralFigures(variant="coral", plan_from="memory episode 4",
                                           attempts=[attempt(0.5, 0.5)])),
        rec("l2r", 0, False, CoralFigures(variant="l2r", plan_from="formulation", attempts=[attempt(1.0, 0.4)])),
        rec("l2r", 1, False, None, error="RuntimeError: boom"),
        rec("expert", 0, True, None), rec("expert", 1, True, None),
    ]


def rows() -> dict[str, dict[str, str]]:
    t = table_i(records(), CFG)
    return {r[1]: dict(zip(t.columns, r)) for r in t.rows}


def test_belief_error_against_the_trials_truth():
    assert belief_error({"box": {"mass_kg": 1.0, "friction": 0.6}}, TRUTH, "box") == pytest.approx((1.0, 0.5))
    assert belief_error({"box": {"mass_kg": 1.0, "friction": 0.6}}, TRUTH, None) == pytest.approx((1.0, 0.5))
    assert belief_error({"board": {"mass_kg": 1.0, "friction": 0.6}}, TRUTH, "board") is None
    assert belief_error(None, TRUTH, "box") is None


def test_table_i_coral_row():
    c = rows()["coral"]
    assert c["Task"] == "flip-box" and c["Success x/n"] == "2/2" and c["% [95% CI]"] == "100 [34–100]"
    assert c["Attempts"] == "1.50"
    assert c["Code / MPPI ms per step"] == "1.67 / 20 (8.3%)"
    assert c["Cost from"] == "formulation 1, memory 1"
    assert c["Belief err. #1 (mass, friction)"] == "50%, 38% (2)"  # (100 + 0) / 2, (50 + 25) / 2
    assert c["Belief err. #2 (mass, friction)"] == "20%, 0% (1)"


def test_table_i_baselines():
    l2r, expert = rows()["l2r"], rows()["expert"]
    assert l2r["Success x/n"] == "0/2" and l2r["Attempts"] == "1.00" and l2r["Err"] == "1"
    assert l2r["Belief err. #1 (mass, friction)"] == "100%, 0% (1)" and l2r["Belief err. #2 (mass, friction)"] == "—"
    assert expert["Success x/n"] == "2/2"
    for col in ("Attempts", "Code / MPPI ms per step", "Cost from", "Belief err. #1 (mass, friction)"):
        assert expert[col] == "—", col


def test_summary_keeps_the_figures_per_task_and_method():
    s = summarize(records())
    assert list(s) == ["flip-box/coral", "flip-box/expert", "flip-box/l2r"]
    coral = s["flip-box/coral"]
    assert coral["successes"] == 2 and coral["mean_attempts"] == 1.5 and coral["code_share"] == 0.0833
    assert coral["belief_error_by_attempt"]["1"] == {"n": 2, "mass": 0.5, "friction": 0.375}
    assert s["flip-box/expert"]["mean_attempts"] is None
