"""System B's Table I from hand-made tabletop records with known numbers (figures through `RunFigures`)."""

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.core.record import TrialRecord
from kintsugi.methods.agentchord.method import RunFigures
from kintsugi.campaign.systems.tabletop import table_i

CFG = CampaignConfig(task="pour-single", methods=["agentchord", "rekep", "scripted"], variants=["default"],
                     conditions=["drop"], trials=4)


def figures(steps: int, calls: tuple[int, int] = (1, 0), latency: list[int] | None = None) -> dict:
    return RunFigures(episode_steps=steps, modelled_execution_time_s=steps / 100 + 5.0 * sum(calls),
                      latency_model_s=5.0, planning_reasoning_calls=calls[0], runtime_reasoning_calls=calls[1],
                      recovery_latency_steps=latency or [], recoveries=len(latency or []), actions=10,
                      graph_nodes=5, graph_edges=6, monitors=3).model_dump()


def rec(method: str, seed: int, success: bool, steps: int | None, **kw) -> TrialRecord:
    return TrialRecord(key=f"pour-single/{method}/default/drop/{seed}", task="pour-single", method=method,
                       variant="default", condition="drop", seed=seed, success=success, framework_success=success,
                       params={"drop_p": 0.1}, sim_time=steps / 100 if steps else 2.0,
                       reasoning_latency_s=0.5 if steps else 0.0,
                       method_figures=figures(steps, **kw) if steps else {})


def records() -> list[TrialRecord]:
    return [
        # AgentChord: seeds 0-2 solved, 3 failed; one recovery of 3 steps on seed 1.
        rec("agentchord", 0, True, 1000), rec("agentchord", 1, True, 1200, latency=[3]),
        rec("agentchord", 2, True, 1100), rec("agentchord", 3, False, 400),
        # ReKep: seeds 0, 1, 3 solved (only 0 and 1 paired), two run-time calls each.
        rec("rekep", 0, True, 1100, calls=(1, 2)), rec("rekep", 1, True, 1500, calls=(1, 2), latency=[5, 9]),
        rec("rekep", 2, False, 300, calls=(1, 2)), rec("rekep", 3, True, 1300, calls=(1, 2)),
        # Scripted: no run figures at all.
        rec("scripted", 0, True, None), rec("scripted", 1, False, None),
    ]


def rows() -> dict[str, dict[str, str]]:
    t = table_i(records(), CFG)
    return {r[0]: dict(zip(t.columns, r)) for r in t.rows}


def test_table_i_agentchord_row():
    ac = rows()["agentchord"]
    assert ac["p"] == "0.1" and ac["n"] == "4" and ac["Success % [95% CI]"] == "75 [30–95]"
    assert ac["Steps"] == "925"  # (1000 + 1200 + 1100 + 400) / 4
    assert ac["Exec s"] == "9.8"  # sim 9.25 + 0.5 s measured latency
    assert ac["Modelled s"] == "14.2"  # sim 9.25 + 5 s per call
    assert ac["Calls plan / run"] == "1.0 / 0.0"
    assert ac["Completed steps / modelled s"] == "1100 / 16.0"
    assert ac["Recoveries"] == "1" and ac["Latency steps"] == "3" and ac["Err"] == "0"
    assert ac["Paired: steps / exec s / modelled s (n)"] == "—"


def test_table_i_paired_against_agentchord_on_the_same_seeds():
    rk = rows()["rekep"]
    assert rk["Calls plan / run"] == "1.0 / 2.0" and rk["Latency steps"] == "9" and rk["Recoveries"] == "2"
    # Seeds 0 and 1: rekep 1300 steps, 13.50 s exec, 28.0 s modelled; agentchord 1100, 11.50, 16.0.
    assert rk["Paired: steps / exec s / modelled s (n)"] == \
        "1300.0 vs 1100.0 / 13.50 vs 11.50 / 28.0 vs 16.0 (2)"
    assert rk["Paired diff"] == "+200.0 / +2.00 / +12.0"


def test_table_i_methods_without_run_figures_show_dashes():
    sc = rows()["scripted"]
    assert sc["Success % [95% CI]"] == "50 [9–91]" and sc["Sim s"] == "2.0"
    for col in ("Steps", "Exec s", "Modelled s", "Calls plan / run", "Completed steps / modelled s",
                "Recoveries", "Latency steps", "Paired: steps / exec s / modelled s (n)",
                "Paired diff"):
        assert sc[col] == "—", col


def test_table_i_keeps_drop_probabilities_apart():
    other = [r.model_copy(update={"params": {"drop_p": 0.05}}) for r in records() if r.method == "agentchord"]
    t = table_i(records() + other, CFG)
    assert [(r[0], r[3]) for r in t.rows] == [("agentchord", "0.1"), ("agentchord", "0.05"), ("rekep", "0.1"),
                                              ("scripted", "0.1")]


def test_table_i_counts_an_errored_trial_without_params_in_its_cell():
    broken = TrialRecord(key="pour-single/agentchord/default/drop/4", task="pour-single", method="agentchord",
                         variant="default", condition="drop", seed=4, error="ImportError: boom")
    t = table_i(records() + [broken], CFG)
    ac = dict(zip(t.columns, t.rows[0]))
    assert len(t.rows) == 3 and ac["p"] == "0.1" and ac["n"] == "5" and ac["Err"] == "1"
