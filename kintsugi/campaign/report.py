"""Write report.md and a self-contained report.html next to a campaign's results.jsonl."""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
import os
import platform
import sys
from pathlib import Path
from typing import Sequence

import kintsugi
from kintsugi.campaign.plan import CampaignConfig
from kintsugi.campaign.plots import plots_for
from kintsugi.campaign.render import to_html, to_markdown
from kintsugi.campaign.runner import error_summary
from kintsugi.campaign.store import ResultStore
from kintsugi.campaign.tables import system_of, tables_for
from kintsugi.core.errors import KintsugiError
from kintsugi.core.record import TrialRecord

_CSS = """
body{font-family:system-ui,sans-serif;margin:2em;max-width:1200px;color:#222}
table{border-collapse:collapse;margin:.5em 0}th,td{border:1px solid #ccc;padding:.25em .6em}
th{background:#f3f3f3}td.r{text-align:right;font-variant-numeric:tabular-nums}td.l{text-align:left}
p.note{color:#666;font-size:.85em;margin:.2em 0}pre{background:#f7f7f7;padding:1em;overflow:auto}
img{max-width:100%}
"""


def machine_info() -> dict[str, str]:
    """Where the numbers came from (timings depend on it)."""
    try:
        import mujoco

        mj = mujoco.__version__
    except Exception:  # noqa: BLE001 - a report must not fail on a missing optional import
        mj = "not installed"
    return {
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": str(os.cpu_count()),
        "python": sys.version.split()[0],
        "mujoco": mj,
        "kintsugi": kintsugi.__version__,
        "commit": _commit(),
    }


def _commit() -> str:
    """The git commit of the kintsugi source the numbers came from (and whether it had local changes)."""
    import subprocess

    src = Path(kintsugi.__file__).resolve().parent
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=src, capture_output=True, text=True,
                              timeout=5)
        if head.returncode:
            return "not a git checkout"
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "."], cwd=src, capture_output=True,
                               text=True, timeout=5).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown (git not available)"
    return head.stdout.strip() + (" with local changes" if dirty else "")


def _videos(out: Path, records: Sequence[TrialRecord]) -> list[tuple[str, str]]:
    """(trial key, path relative to the report) of every recorded video that exists."""
    found = []
    for r in records:
        if r.video and Path(r.video).exists():
            found.append((r.key, os.path.relpath(Path(r.video).resolve(), out.resolve())))
    return found


def _write(path: Path, text: str) -> None:
    try:
        path.write_text(text)
    except OSError as exc:
        raise KintsugiError(f"cannot write the report {path}: {exc}") from None


def _records_for(cfg: CampaignConfig, records: Sequence[TrialRecord]) -> list[TrialRecord]:
    from kintsugi.campaign.plan import expand

    wanted = {s.key for s in expand(cfg)}
    return [r for r in records if r.key in wanted]


def _trials_html(recs: Sequence[TrialRecord], pages: dict[str, str]) -> str:
    """A table of the trials, each linked to its page (relative to the report)."""
    if not pages:
        return ""
    esc = html.escape
    rows = "".join(
        f'<tr><td class="l"><a href="{esc(pages[r.key])}">{esc(r.key)}</a></td>'
        f'<td class="l">{"success" if r.success else "failure"}</td>'
        f'<td class="l">{"success" if r.framework_success else "failure"}</td>'
        f'<td class="r">{r.sim_time:.1f}</td><td class="r">{r.reasoning_calls}</td>'
        f'<td class="l">{esc((r.error or "").splitlines()[0][:120]) if r.error else ""}</td></tr>'
        for r in recs if r.key in pages)
    return ("<h2>Trials</h2><table><thead><tr><th>trial</th><th>ground truth</th><th>verdict</th><th>sim s</th>"
            f"<th>calls</th><th>error</th></tr></thead><tbody>{rows}</tbody></table>")


def write_report(
    out_dir: str | Path,
    cfg: CampaignConfig | None = None,
    records: Sequence[TrialRecord] | None = None,
    trial_pages: dict[str, str] | None = None,
) -> tuple[Path, Path]:
    """Write report.md and report.html into `out_dir`; config and records default to what it holds.

    Only records belonging to the config's trials are reported (a campaign whose
    trial count shrank keeps its extra lines on disk, but they are not counted). The tables and
    plots are those of the task's system (`tables_for`), the generic ones for a task of no system.
    `trial_pages` ({key: path relative to `out_dir`}) adds a table of the trials linking their pages.
    """
    out = Path(out_dir)
    store = ResultStore(out)
    cfg = cfg or store.load_config()
    recs = _records_for(cfg, store.read() if records is None else records)
    system = system_of(cfg.task, cfg)
    tables = tables_for(system or cfg.task, recs, cfg)
    info = machine_info()
    cfg_json = json.dumps(cfg.model_dump(mode="json"), indent=2)
    summary = f"{len(recs)} of {len(cfg.cells()) * cfg.trials} trials recorded; task `{cfg.task}`."
    errors = error_summary(recs)
    if errors:
        summary += f" {errors}."

    md = [f"# kintsugi campaign report — {cfg.task}", "", summary, ""]
    md += [to_markdown(t) for t in tables]
    videos = _videos(out, recs)
    if videos:
        md += ["## Videos", ""] + [f"- [{key}]({rel})" for key, rel in videos] + [""]
    pages = {r.key: trial_pages[r.key] for r in recs if trial_pages and r.key in trial_pages}
    if pages:
        md += ["## Trials", "", "| trial | ground truth | verdict |", "|---|---|---|"]
        md += [f"| [{r.key}]({pages[r.key]}) | {'success' if r.success else 'failure'} | "
               f"{'success' if r.framework_success else 'failure'} |" for r in recs if r.key in pages] + [""]
    md += ["## Campaign config", "", "```json", cfg_json, "```", "", "## Machine", ""]
    md += [f"- {k}: {v}" for k, v in info.items()]
    md_path = out / "report.md"
    _write(md_path, "\n".join(md) + "\n")

    figs = "".join(
        f'<img alt="campaign plot" src="data:image/png;base64,{base64.b64encode(png).decode()}">'
        for png in plots_for(system, recs, cfg)
    )
    esc = html.escape
    body = [
        f"<h1>kintsugi campaign report — {esc(cfg.task)}</h1><p>{esc(summary)}</p>",
        *[to_html(t) for t in tables],
        f"<h2>Plots</h2>{figs}" if figs else "",
        ("<h2>Videos</h2><ul>" + "".join(f'<li><a href="{esc(rel)}">{esc(key)}</a></li>' for key, rel in videos)
         + "</ul>") if videos else "",
        _trials_html(recs, pages),
        f"<h2>Campaign config</h2><pre>{esc(cfg_json)}</pre>",
        "<h2>Machine</h2><ul>" + "".join(f"<li>{esc(k)}: {esc(v)}</li>" for k, v in info.items()) + "</ul>",
    ]
    page = (
        '<!doctype html><html><head><meta charset="utf-8">'
        f"<title>kintsugi report — {esc(cfg.task)}</title><style>{_CSS}</style></head>"
        f"<body>{''.join(body)}</body></html>\n"
    )
    html_path = out / "report.html"
    _write(html_path, page)
    return md_path, html_path
