"""System A's Tables II/III, the generic tables and the dispatch by system, from hand-made records with known numbers."""

from io import StringIO

from rich.console import Console

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.render import print_tables, to_html, to_markdown
from kintsugi.campaign.tables import register_tables, success_table, tables_for, timing_table, TextTable
from kintsugi.core.record import TrialRecord
from kintsugi.core.registry import TASKS
from kintsugi.methods.recovery.skill_log import PegFigures
from kintsugi.campaign.systems.peg import table_ii, table_iii


def rec(method, condition, seed, **kw):
    return TrialRecord(key=f"peg/{method}/round/{condition}/{seed}", task="peg", method=method,
                       variant="round", condition=condition, seed=seed, **kw)


CFG = CampaignConfig(task="peg", methods=["none", "vlm"], variants=["round"], conditions=["all", "friction"], trials=30)


def records():
    out = []
    # Baseline, "all": 14/30 G, 15/30 F, no recovery at all.
    for i in range(30):
        out.append(rec("none", "all", i, success=i < 14, framework_success=i < 15, wall_time=1.0 + i))
    # Recovery, "all": 25/30 G and F, one errored trial (seed 29, counted as failure and in Err).
    for i in range(30):
        extra = {"fit": 1, "align": 2 if i % 2 else 0, "insert": 0}
        transitions = [("fit", "fit"), ("align", "fit") if i < 3 else ("align", "align")]
        out.append(rec("vlm", "all", i, success=i < 25, framework_success=i < 25,
                       method_figures=PegFigures(extra_executions=extra).model_dump(), transitions=transitions, reasoning_calls=4, reasoning_latency_s=2.0,
                       error="boom" if i == 29 else None))
    # Recovery, "friction": needs no recovery -> 0.0, not "—".
    for i in range(30):
        out.append(rec("vlm", "friction", i, success=True, framework_success=True,
                       method_figures={"extra_executions": {"fit": 0}}))
    return out


def test_table_ii_numbers():
    t = table_ii(records(), CFG)
    assert t.columns[:7] == ["Method", "Variant", "Condition", "n", "Fit", "Align", "Insert"]
    rows = {(r[0], r[2]): r for r in t.rows}
    assert [(r[0], r[2]) for r in t.rows] == [("none", "all"), ("vlm", "all"), ("vlm", "friction")]
    none_all = rows[("none", "all")]
    assert none_all[3:] == ["30", "—", "—", "—", "50 [33–67]", "47 [30–64]", "1", "0", "0"]  # seed 14: F+G-
    vlm_all = rows[("vlm", "all")]
    # 29 trials without error: fit 1.0; align 2 on odd seeds 1..27 -> 14*2/29 = 0.97
    assert vlm_all[4:7] == ["1.0", "1.0", "0.0"]
    assert vlm_all[7:] == ["83 [66–93]", "83 [66–93]", "0", "0", "1"]
    assert rows[("vlm", "friction")][4:] == ["0.0", "0.0", "0.0", "100 [89–100]", "100 [89–100]", "0", "0", "0"]


def test_table_ii_explicit_recovering_methods():
    t = table_ii(records(), CFG, recovering={"none", "vlm"})
    assert t.rows[0][4:7] == ["0.0", "0.0", "0.0"]


def test_table_iii_row_percentages():
    tables = table_iii(records(), CFG)
    assert len(tables) == 1 and "vlm / round" in tables[0].title
    rows = {r[0]: r for r in tables[0].rows}
    assert rows["Fit"][1:] == ["100.0% (30)", "0.0% (0)", "0.0% (0)", "30"]
    assert rows["Align"][1:] == ["10.0% (3)", "90.0% (27)", "0.0% (0)", "30"]
    assert rows["Insert"][1:] == ["—", "—", "—", "0"]


def test_timing_table():
    t = timing_table(records(), CFG)
    rows = {(r[0], r[2]): r for r in t.rows}
    assert rows[("none", "all")][4] == "15.50"  # median of 1..30
    assert rows[("vlm", "all")][7] == "4.0" and rows[("vlm", "all")][8] == "0.500"
    assert rows[("none", "all")][8] == "—"


def test_renderings_contain_the_numbers():
    t = table_ii(records(), CFG)
    md = to_markdown(t)
    assert "| vlm | round | all | 30 | 1.0 | 1.0 | 0.0 | 83 [66–93] | 83 [66–93] | 0 | 0 | 1 |" in md
    assert "<td class=\"r\">83 [66–93]</td>" in to_html(t)
    buf = StringIO()
    print_tables([t, *table_iii(records(), CFG)], Console(file=buf, width=60))
    text = buf.getvalue()
    assert "83 [66–93]" in text and "90.0% (27)" in text  # widened, not cropped, when piped


def test_tables_without_config_use_record_order():
    t = table_ii(list(reversed(records())))
    assert [r[0] for r in t.rows] == ["vlm", "vlm", "none"]


def test_older_records_keep_their_extra_executions():
    old = TrialRecord.model_validate({"key": "peg/vlm/round/all/0", "task": "peg", "method": "vlm", "variant": "round",
                                      "condition": "all", "seed": 0, "extra_executions": {"Fit": 2}})
    assert table_ii([old]).rows[0][4] == "2.0"


def test_success_table():
    t = success_table(records(), CFG)
    assert t.columns == ["Method", "Variant", "Condition", "n", "Success % [95% CI]", "Verdict % [95% CI]",
                         "False succ.", "Err"]
    rows = {(r[0], r[2]): r for r in t.rows}
    assert rows[("none", "all")][3:] == ["30", "47 [30–64]", "50 [33–67]", "1", "0"]
    assert rows[("vlm", "all")][3:] == ["30", "83 [66–93]", "83 [66–93]", "0", "1"]


def test_tables_for_peg_system():
    titles = [t.title for t in tables_for("peg", records(), CFG)]
    assert titles[0].startswith("Table II") and titles[1].startswith("Table III")
    assert titles[2:] == ["Success per cell", "Cost per cell"]


def test_tables_for_peg_task_by_its_system_attribute():
    cfg = CFG.model_copy(update={"task": "peg-insertion"})
    recs = [r.model_copy(update={"task": "peg-insertion"}) for r in records()]
    assert tables_for("peg-insertion", recs, cfg)[0].title.startswith("Table II")


class _NoSystemTask:
    """A plugin task that names no system."""


def test_unknown_system_gets_the_generic_tables_only():
    if "test-no-system" not in TASKS:
        TASKS.register("test-no-system", "a task of no system", tags=("test",))(_NoSystemTask)
    for name in ("no-such-task", "test-no-system"):
        cfg = CFG.model_copy(update={"task": name})
        assert [t.title for t in tables_for(name, records(), cfg)] == ["Success per cell", "Cost per cell"]


def test_a_plugin_system_registers_its_tables():
    register_tables("test-system", lambda recs, cfg: [TextTable("Own", ["n"], [[str(len(recs))]])])
    tables = tables_for("test-system", records(), CFG)
    assert tables[0].title == "Own" and tables[0].rows == [["90"]] and len(tables) == 3
