"""report.md and the self-contained report.html from a real (inline) fake campaign."""

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.report import write_report
from kintsugi.campaign.runner import run_campaign


def test_report_files(tmp_path):
    cfg = CampaignConfig(task="fake-coin", methods=["plain", "recover"], variants=["fair", "raises"],
                         conditions=["easy", "hard"], trials=4, plugins=["tests.fake_tasks"])
    run_campaign(cfg, tmp_path, executor="inline", progress=False)
    md_path, html_path = write_report(tmp_path)
    assert md_path == tmp_path / "report.md" and html_path == tmp_path / "report.html"
    md = md_path.read_text()
    assert "Table II" in md and "Table III" in md and "Cost per cell" in md
    assert '"task": "fake-coin"' in md and "mujoco:" in md and "cpu_count:" in md
    html = html_path.read_text()
    assert html.count('<img alt="campaign plot" src="data:image/png;base64,') == 2
    assert "<table>" in html and "fake-coin" in html


def test_report_only_counts_the_configs_trials(tmp_path):
    cfg = CampaignConfig(task="fake-coin", methods=["plain"], variants=["fair"], conditions=["easy"],
                         trials=6, plugins=["tests.fake_tasks"])
    run_campaign(cfg, tmp_path, executor="inline", progress=False)
    small = cfg.model_copy(update={"trials": 2})
    md_path, _ = write_report(tmp_path, cfg=small)
    assert "2 of 2 trials recorded" in md_path.read_text()
