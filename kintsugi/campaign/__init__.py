"""Campaigns: many trials in parallel, appended as they finish, resumable, summarized as the papers' tables.

Entry points (import from the submodules; this package stays light so spawned
workers do not import rich/matplotlib):

- plan.CampaignConfig, plan.expand(cfg, video_dir=None) -> list[TrialSpec]
- runner.run_campaign(cfg, out_dir, workers=2, executor="process", progress=True) -> list[TrialRecord]
- executors.EXECUTORS (registry: process, inline, ray)
- store.ResultStore(out_dir): .read(), .done_keys(), .load_config()
- tables.tables_for(task or system, records, cfg) -> list[TextTable]: the system's own tables
  (kintsugi/campaign/systems/) + success_table + timing_table
- render.print_tables(tables, console), to_markdown, to_html
- report.write_report(out_dir, cfg=None, records=None) -> (report.md, report.html)
"""
