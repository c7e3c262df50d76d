"""Benchmark pages are written by the bench scripts: each script owns a marked block of its page, with the
command, date, commit and machine, and the page's hand-written text stays."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bench.pages import Block, campaign_tables, main, write_block

ROOT = Path(__file__).resolve().parents[2]


def test_a_block_is_appended_then_replaced_and_the_text_around_it_stays(tmp_path: Path) -> None:
    page = tmp_path / "b.md"
    page.write_text("# Bench\n\nHand-written notes.\n")
    write_block(page, Block("t", "bench/t.py --run", ["| a | b |", "|---|---|", "| 1 | 2 |"]))
    write_block(page, Block("other", "bench/o.py", ["x"]))
    write_block(page, Block("t", "bench/t.py --run", ["| a | b |", "|---|---|", "| 3 | 4 |"]))
    text = page.read_text()
    assert text.startswith("# Bench\n\nHand-written notes.\n") and text.count("<!-- begin: t -->") == 1
    assert "| 3 | 4 |" in text and "| 1 | 2 |" not in text and "<!-- begin: other -->" in text
    assert "Written by `bench/t.py --run` on " in text and "commit " in text and "CPUs" in text
    assert write_block(tmp_path / "new.md", Block("n", "c", ["y"]), title="New").read_text().startswith("# New")


def test_campaign_tables_go_into_a_page(tmp_path: Path) -> None:
    from kintsugi.campaign.plan import build_config
    from kintsugi.campaign.runner import run_campaign

    cfg = build_config(task="peg-insertion", methods=["baseline"], variants=["round"], conditions=["none"], trials=2)
    run_campaign(cfg, tmp_path / "c", executor="inline", progress=False)
    lines = campaign_tables(tmp_path / "c")
    assert any(line.startswith("| ") for line in lines) and "2 recorded" in lines[0]
    assert main([str(tmp_path / "p.md"), "peg", str(tmp_path / "c")]) == 0
    assert "<!-- begin: peg -->" in (tmp_path / "p.md").read_text()
    assert main([]) == 2


@pytest.mark.slow
def test_bench_peg_writes_its_page(tmp_path: Path) -> None:
    page = tmp_path / "benchmarks-peg.md"
    res = subprocess.run([sys.executable, "bench/bench_peg.py", "--trials", "2", "--repeats", "1", "--page", str(page)],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    text = page.read_text()
    assert "<!-- begin: bench_peg -->" in text and "| framework overhead (raw / framework) |" in text
    assert "Written by `.venv/bin/python bench/bench_peg.py --trials 2 --repeats 1 --page" in text


@pytest.mark.slow
def test_the_agentchord_and_coral_table_scripts_write_their_pages(tmp_path: Path) -> None:
    from kintsugi.campaign.plan import build_config
    from kintsugi.campaign.runner import run_campaign
    from kintsugi.core.record import TrialRecord

    cfg = build_config(task="pour-single", methods=["scripted"], variants=["default"], conditions=["none"], trials=1)
    run_campaign(cfg, tmp_path / "b", executor="inline", progress=False)
    coral = tmp_path / "c.jsonl"
    coral.write_text(TrialRecord(key="flip-box/coral/default/all/0", task="flip-box", method="coral",
                                 variant="default", condition="all", seed=0, success=True).model_dump_json() + "\n")
    for script, arg, block in (("bench_agentchord_table.py", tmp_path / "b", "bench_agentchord_table"),
                               ("bench_coral.py", coral, "bench_coral")):
        page = tmp_path / f"{block}.md"
        res = subprocess.run([sys.executable, f"bench/{script}", str(arg), "--page", str(page)], cwd=ROOT,
                             capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr[-2000:]
        text = page.read_text()
        assert f"<!-- begin: {block} -->" in text and "| " in text and f"bench/{script}" in text


def _campaign(out: Path, base_seed: int, wins: dict[str, int], trials: int = 10) -> Path:
    """A campaign directory holding `wins[method]` successes of `trials` per method (records written directly)."""
    from kintsugi.campaign.plan import build_config, expand
    from kintsugi.campaign.store import ResultStore
    from kintsugi.core.record import TrialRecord

    cfg = build_config(task="pour-single", methods=list(wins), variants=["default"], conditions=["drop"],
                       trials=trials, base_seed=base_seed)
    store = ResultStore(out)
    store.ensure_manifest(cfg)
    with store.appender() as app:
        for s in expand(cfg):
            app.append(TrialRecord(**s.identity(), success=s.seed - base_seed < wins[s.method],
                                   method_figures={"episode_steps": 1000 + s.seed - base_seed}))
    return out


def test_fresh_seeds_say_what_moved_against_campaigns_and_against_a_page_table(tmp_path: Path) -> None:
    from bench.fresh import main as fresh_main

    dev = _campaign(tmp_path / "dev", 0, {"agentchord": 10, "rekep": 9})
    fresh = _campaign(tmp_path / "fresh", 10000, {"agentchord": 10, "rekep": 5})
    page = tmp_path / "p.md"
    assert fresh_main([str(fresh), "--dev", str(dev), "--figure", "steps", "--page", str(page), "--name", "f"]) == 0
    text = page.read_text()
    assert "| agentchord | 100 [72–100] (10/10) | 100 [72–100] (10/10) | 0 | 1004 → 1004 | 0.00 → 0.00 |" in text
    assert "- rekep: 90 % → 50 % (-40 points; fresh 50 [24–76] (5/10)), outside the development interval" in text
    assert "- 1 cell unchanged; 1 outside the development interval (rekep)." in text
    assert "20 fresh trials, 15 successes overall" in text and "Written by `" in text

    table = tmp_path / "dev.md"
    table.write_text("## Table I\n\n| task | method | success % [95 % CI] | steps |\n|---|---|---|---|\n"
                     "| pour-single | agentchord | **100 [72–100]** | 1004 |\n| pour-single | rekep | 50 [24–76] | 990 |\n")
    assert fresh_main([str(fresh), "--dev-table", str(table), "Table I", "--page", str(page), "--name", "f"]) == 0
    text = page.read_text()
    assert "No success rate moved." in text and "0 outside" in text and text.count("<!-- begin: f -->") == 1
    with pytest.raises(SystemExit):
        fresh_main([str(fresh)])  # the development figures are required


def test_fresh_seeds_read_a_table_with_one_column_per_method(tmp_path: Path) -> None:
    """System C's pages give one row per task and one column per method (`k/n [low–high]` or `k/n`)."""
    from bench.fresh import page_cells

    table = tmp_path / "c.md"
    table.write_text("**CoRAL and its ablations.**\n\n| task | coral | l2r | expert-fsm [95 % CI] | paper /10 |\n"
                     "|---|---|---|---|---|\n| flip-box (T5) | 10/10 [72–100], 1.0 attempts | 4/10 | 9/10 [60–98] | 9 |\n")
    cells = page_cells(str(table), "CoRAL and its ablations")
    assert {k[:2]: (f.k, f.n) for k, f in cells.items()} == {
        ("flip-box", "coral"): (10, 10), ("flip-box", "l2r"): (4, 10), ("flip-box", "expert-fsm"): (9, 10)}
    assert round(cells[("flip-box", "l2r", None, None)].low) == 17
