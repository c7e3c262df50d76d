"""report.md and the self-contained report.html: a real (inline) fake peg-system campaign, and each
system's own tables from hand-made records."""

import re
from io import StringIO

import pytest
from rich.console import Console

from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.render import print_tables
from kintsugi.campaign.report import write_report
from kintsugi.campaign.runner import run_campaign
from kintsugi.campaign.tables import tables_for
from tests.methods.agentchord.test_agentchord_tables import records as agentchord_records
from tests.methods.coral.test_coral_tables import records as coral_records


def test_report_files(tmp_path):
    cfg = CampaignConfig(task="fake-coin", methods=["plain", "recover"], variants=["fair", "raises"],
                         conditions=["easy", "hard"], trials=4, plugins=["tests.fake_tasks"])
    run_campaign(cfg, tmp_path, executor="inline", progress=False)
    md_path, html_path = write_report(tmp_path)
    assert md_path == tmp_path / "report.md" and html_path == tmp_path / "report.html"
    md = md_path.read_text()
    assert "Table II" in md and "Table III" in md and "Success per cell" in md and "Cost per cell" in md
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


PEG_WORDING = ("peg", "Fit", "Align", "Insert", "Table II", "Table III")


@pytest.mark.parametrize(("builder", "system_table"), [
    (agentchord_records, "Table I — success, steps"), (coral_records, "Table I — success, attempts")])
def test_tabletop_and_contact_reports_carry_their_own_tables_without_peg_wording(tmp_path, builder, system_table):
    records = builder()
    cfg = CampaignConfig(task=records[0].task, methods=list(dict.fromkeys(r.method for r in records)),
                         variants=["default"], conditions=[records[0].condition], trials=4)
    buf = StringIO()
    print_tables(tables_for(cfg.task, records, cfg), Console(file=buf, width=300))
    md_path, html_path = write_report(tmp_path, cfg, records)
    page = re.sub(r'<img [^>]*>', "", html_path.read_text())  # base64 plots may spell anything
    for text in (buf.getvalue(), md_path.read_text(), page):
        assert system_table in text and "Success per cell" in text and "Cost per cell" in text
        assert not [w for w in PEG_WORDING if w in text]
