"""Browser pages: `kintsugi report` writes a page per trial beside report.html and, over a directory of
campaigns, an index; every link is relative and resolves, every page shows what its trial holds."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote

import pytest
from typer.testing import CliRunner

from kintsugi.cli import app
from kintsugi.cli.pages import write_trial_page
from kintsugi.core.record import TrialRecord, TrialSpec

runner = CliRunner()


def links(page: Path) -> list[str]:
    return [x for x in re.findall(r'(?:href|src)="([^"#]+)"', page.read_text()) if not x.startswith("data:")]


def assert_links_resolve(page: Path) -> None:
    for link in links(page):
        assert not link.startswith(("/", "file:", "http")), (page, link)  # relative: the directory can move
        assert (page.parent / unquote(link)).exists(), (page, link)


@pytest.mark.slow
def test_report_writes_linked_trial_pages_and_an_index(tmp_path: Path) -> None:
    camp = tmp_path / "tour" / "a-peg"
    res = runner.invoke(app, ["bench", "peg-insertion", "--methods", "baseline,recovery", "--conditions", "all",
                              "--trials", "2", "--videos-per-cell", "1", "--executor", "inline",
                              "--out", str(camp)])
    assert res.exit_code == 0, res.output
    report = camp / "report.html"
    pages = [link for link in links(report) if link.startswith("trials/")]
    assert len(pages) == 4  # a page per trial, linked from the report
    assert_links_resolve(report)
    for link in pages:
        page = camp / link
        assert_links_resolve(page)
        text = page.read_text()
        assert "<h2>Timeline</h2>" in text and "ground truth" in text and "../report.html" in text
        if "recovery" in link:
            assert "<h2>Reasoning calls</h2><table>" in text and "judge" in text
        if link.endswith("__0.html"):
            assert "<video" in text  # the first trial of each cell has a video
    res = runner.invoke(app, ["report", str(tmp_path / "tour")])
    assert res.exit_code == 0, res.output
    index = tmp_path / "tour" / "index.html"
    assert_links_resolve(index)
    text = index.read_text()
    assert "a-peg/report.html" in text and "<video" in text and "__recovery__" in text.split("<video")[1][:200]
    assert "<h3>Table II" in text


def test_a_trial_page_shows_the_planner_plot_and_the_composer_graph(tmp_path: Path) -> None:
    from tests.taskgraph_fixtures import pour_graph_data

    (tmp_path / "videos").mkdir()
    (tmp_path / "report.html").write_text("<html></html>")
    video = tmp_path / "videos" / "t.mp4"
    video.write_bytes(b"not really a video")
    video.with_suffix(".plan.png").write_bytes(b"png")
    spec = TrialSpec(task="flip-box", method="coral", variant="default", condition="all", seed=0)
    rec = TrialRecord(**spec.identity(), success=True, framework_success=True, video=str(video),
                      transcript=[{"role": "composer", "backend": "embedded", "request": {},
                                   "reply": {"graph": pour_graph_data()}, "latency_s": 0.01},
                                  {"role": "arranger", "backend": "embedded", "request": {"a": "<b>"},
                                   "reply": None, "error": "refused <script>", "latency_s": 0.02}])
    page = write_trial_page(rec, tmp_path / "trials")
    assert_links_resolve(page)
    text = page.read_text()
    assert 'src="../videos/t.mp4"' in text and 'src="../videos/t.plan.png"' in text
    assert "<h2>Task graph</h2>" in text and (tmp_path / "trials" / (page.stem + ".graph.html")).exists()
    assert "<script>" not in text and "refused &lt;script&gt;" in text  # record text is escaped


def test_a_system_b_trial_page_shows_the_graph_it_ran_on_with_its_recovery_branches(tmp_path: Path) -> None:
    import json

    golden = Path(__file__).resolve().parents[1] / "data" / "golden" / "records.jsonl"
    data = next(d["record"] for d in map(json.loads, golden.read_text().splitlines())
                if d["record"]["key"] == "pour-single/agentchord/default/drop/0")
    rec = TrialRecord.model_validate(data)
    (tmp_path / "report.html").write_text("<html></html>")
    page = write_trial_page(rec, tmp_path / "trials")
    assert_links_resolve(page)
    text = page.read_text()
    assert "the arranger&#x27;s recovery branches (24 kept by the forward filter, 0 rejected); 52 nodes" in text
    view = (tmp_path / "trials" / (page.stem + ".graph.html")).read_text()
    composed = data["transcript"][0]["reply"]["graph"]
    assert view.count('<g class="box">') > len(composed["nodes"]) + len(composed["edges"])  # recovery boxes too
    assert 'stroke-dasharray="4,2"' in view  # recovery boxes are drawn dashed


def test_report_index_only_links_the_reports_bench_wrote_and_rewrites_none(tmp_path: Path) -> None:
    from kintsugi.campaign.plan import build_config
    from kintsugi.campaign.store import ResultStore

    root = tmp_path / "tour"
    for name in ("a", "b"):
        ResultStore(root / name).ensure_manifest(build_config(task="peg-insertion", methods=["baseline"],
                                                              variants=["round"], conditions=["none"], trials=1))
    (root / "a" / "report.html").write_text("<html><body><h3>Table II</h3><table></table></body></html>")
    res = runner.invoke(app, ["report", str(root), "--index-only"])
    assert res.exit_code == 2 and "b has no report.html" in res.output.replace("\n", "")
    (root / "b" / "report.html").write_text("<html><body>kept</body></html>")
    res = runner.invoke(app, ["report", str(root), "--index-only"])
    assert res.exit_code == 0, res.output
    assert (root / "b" / "report.html").read_text() == "<html><body>kept</body></html>"
    assert 'href="a/report.html"' in (root / "index.html").read_text()
    assert runner.invoke(app, ["report", str(root / "a"), "--index-only"]).exit_code == 2
