"""Browser pages of a campaign's trials, beside its report.html, and an index over several campaigns.

`trials/<key>.html` per trial: the outcome, the video (and, for System C, the planner plot beside it),
the explain timeline with sim and wall time, every reasoning call (role, latency, the reply's gist,
the request and reply behind a fold), and for System B the task graph the trial ran on: the composer's
graph with the arranger's recovery branches, and each re-plan's (an interactive view,
`trials/<key>.graph.html`). Every link is relative, so a campaign directory can be
moved, zipped or served as it is.
"""

from __future__ import annotations

import html
import io
import json
import os
from pathlib import Path
from typing import Sequence

from rich.console import Console

from kintsugi.cli.explain import explain_record, gist
from kintsugi.core.errors import KintsugiError
from kintsugi.core.record import TrialRecord

_CSS = """body{font-family:system-ui,sans-serif;margin:1.5em;max-width:1200px;color:#222}
pre{background:#fafafa;padding:.8em;overflow:auto;font-size:12px;white-space:pre-wrap}
.ok{color:#1a7f37}.bad{color:#c62828}video,img{max-width:100%}table{border-collapse:collapse}
td,th{border:1px solid #ccc;padding:.2em .5em;vertical-align:top}details{margin:.2em 0}
iframe{width:100%;height:70vh;border:1px solid #ccc}"""


def page_name(key: str) -> str:
    return key.replace("/", "__") + ".html"


def _page(title: str, body: str) -> str:
    return (f'<!doctype html><html><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
            f"<style>{_CSS}</style></head><body>{body}</body></html>\n")


def _rel(target: str | Path, base: Path) -> str | None:
    path = Path(target)
    return os.path.relpath(path.resolve(), base.resolve()) if path.exists() else None


def _timeline(rec: TrialRecord) -> str:
    buffer = io.StringIO()
    console = Console(file=buffer, width=130, record=True, soft_wrap=False, color_system=None)
    explain_record(rec, console)
    return html.escape(console.export_text())


def _calls(rec: TrialRecord) -> str:
    if not rec.transcript:
        return "<p>No reasoning calls.</p>"
    rows = []
    for i, call in enumerate(rec.transcript, 1):
        raw = json.dumps({k: call.get(k) for k in ("request", "reply", "error")}, indent=1, default=str)
        rows.append(f"<tr><td>{i}</td><td>{html.escape(str(call.get('role')))}</td>"
                    f"<td>{html.escape(str(call.get('backend')))}</td><td>{call.get('latency_s', 0.0):.3f} s</td>"
                    f"<td>{html.escape(gist(call))}<details><summary>request and reply</summary>"
                    f"<pre>{html.escape(raw[:200_000])}</pre></details></td></tr>")
    return ("<table><tr><th>#</th><th>role</th><th>backend</th><th>latency</th><th>answer</th></tr>"
            + "".join(rows) + "</table>")


def compiled_graphs(rec: TrialRecord) -> list[tuple[str, object]]:
    """The task graphs a System B trial ran on, from its transcript: for each composer reply, the graph with the
    arranger's recovery branches inserted and filtered (Eq. 8) as the method ran it, else the composer's alone.
    Returns [(caption, TaskGraph)], first the initial plan, then every re-plan; a graph that does not validate
    is a caption with None."""
    from kintsugi.taskgraph.augment import augment, parse_proposals
    from kintsugi.taskgraph.forward import forward_filter
    from kintsugi.taskgraph.model import TaskGraph

    calls = [c for c in rec.transcript if isinstance(c.get("reply"), dict)]
    out: list[tuple[str, object]] = []
    for i, call in enumerate(calls):
        if call.get("role") != "composer" or not isinstance(call["reply"].get("graph"), dict):
            continue
        nxt = next((c for c in calls[i + 1:] if c.get("role") in ("composer", "arranger")), None)
        proposals = nxt["reply"].get("proposals") if nxt is not None and nxt.get("role") == "arranger" else None
        which = "the plan" if not out else f"re-plan {len(out)}"
        try:
            nominal = TaskGraph.from_data(call["reply"]["graph"])
            if proposals is None:
                out.append((f"{which}: the composer's graph (no arranger call: no recovery branches)", nominal))
                continue
            res = forward_filter(augment(nominal, parse_proposals(proposals)))
            out.append((f"{which}: the composer's graph with the arranger's recovery branches "
                        f"({len(res.kept)} kept by the forward filter, {len(res.rejected)} rejected)", res.graph))
        except (KintsugiError, ValueError):
            out.append((f"{which}: the graph in this record does not validate", None))
    return out


def _graph(rec: TrialRecord, trials_dir: Path) -> str:
    """A System B trial's task graphs (recovery-augmented) as interactive pages; '' when the record has none."""
    from kintsugi.taskgraph.render import graph_html

    parts = []
    for i, (caption, graph) in enumerate(compiled_graphs(rec)):
        if graph is None:
            parts.append(f"<p>{html.escape(caption)}.</p>")
            continue
        name = rec.key.replace("/", "__") + (".graph.html" if i == 0 else f".graph{i}.html")
        (trials_dir / name).write_text(graph_html(graph))
        n_nodes = len(graph.nodes)
        link = f'<a href="{html.escape(name)}">open it alone</a>'
        text = f"<p>{html.escape(caption)}; {n_nodes} nodes, {len(graph.edges)} edges. {link}</p>"
        parts.append(text + (f'<iframe src="{html.escape(name)}"></iframe>' if i == 0 else ""))
    return "<h2>Task graph</h2>" + "".join(parts) if parts else ""


def write_trial_page(rec: TrialRecord, trials_dir: Path, report: str = "../report.html") -> Path:
    """One trial's page in `trials_dir`; returns its path."""
    trials_dir.mkdir(parents=True, exist_ok=True)
    esc = html.escape
    verdict = (f'<span class="{"ok" if rec.success else "bad"}"><b>ground truth '
               f'{"SUCCESS" if rec.success else "FAILURE"}</b></span>, the method\'s verdict '
               f'{"success" if rec.framework_success else "failure"}; sim {rec.sim_time:.2f} s, wall '
               f'{rec.wall_time:.2f} s, {rec.reasoning_calls} reasoning calls')
    parts = [f'<p><a href="{esc(report)}">&larr; campaign report</a></p><h1>{esc(rec.key)}</h1><p>{verdict}</p>']
    if rec.error:
        parts.append(f'<pre class="bad">{esc(rec.error)}</pre>')
    video = _rel(rec.video, trials_dir) if rec.video else None
    if video:
        parts.append(f'<h2>Video</h2><video controls preload="metadata" src="{esc(video)}"></video>'
                     f'<p><a href="{esc(video)}">{esc(Path(video).name)}</a></p>')
        plan = _rel(Path(rec.video).with_suffix(".plan.png"), trials_dir)
        if plan:
            parts.append(f'<h2>Planner</h2><img alt="MPPI cost, temperature and ESS" src="{esc(plan)}">')
    parts.append(_graph(rec, trials_dir))
    parts.append(f"<h2>Timeline</h2><pre>{_timeline(rec)}</pre>")
    parts.append(f"<h2>Reasoning calls</h2>{_calls(rec)}")
    path = trials_dir / page_name(rec.key)
    path.write_text(_page(rec.key, "".join(parts)))
    return path


def write_trial_pages(out: Path, records: Sequence[TrialRecord]) -> dict[str, str]:
    """A page per trial under `out/trials/`; returns {trial key: page path relative to `out`}."""
    trials = Path(out) / "trials"
    try:
        return {r.key: os.path.relpath(write_trial_page(r, trials), out) for r in records}
    except OSError as exc:
        raise KintsugiError(f"cannot write the trial pages under {trials}: {exc}") from None


def _own_method(campaign: Path) -> str:
    """The system's own method of a campaign's task ('' when it cannot be told)."""
    from kintsugi.campaign.plan import task_defaults
    from kintsugi.campaign.store import ResultStore

    try:
        cfg = ResultStore(campaign).load_config()
        return task_defaults(cfg.task, cfg.plugins)[0]
    except KintsugiError:
        return ""


def write_index(root: Path, campaigns: Sequence[Path], title: str = "kintsugi") -> Path:
    """`root/index.html`: each campaign's report (its tables inline) and its first video, linked relatively."""
    import re

    esc = html.escape
    parts = [f"<h1>{esc(title)}</h1>"]
    for c in campaigns:
        report = c / "report.html"
        if not report.exists():
            continue
        text = report.read_text()
        body = re.search(r"<body>(.*)</body>", text, flags=re.S)
        tables = re.findall(r"<h3>[^<]*</h3>\s*<table.*?</table>(?:<p class=\"note\">.*?</p>)*",
                            body.group(1) if body else "", flags=re.S)
        rel = os.path.relpath(report, root)
        parts.append(f'<h2><a href="{esc(rel)}">{esc(c.name)}</a></h2>')
        videos = sorted((c / "videos").glob("*.mp4")) if (c / "videos").is_dir() else []
        own = _own_method(c)
        videos.sort(key=lambda v: f"__{own}__" not in v.name)  # the system's own method's first
        if videos:
            v = os.path.relpath(videos[0], root)
            parts.append(f'<video controls preload="metadata" width="640" src="{esc(v)}"></video>')
        parts += tables
    path = root / "index.html"
    path.write_text(_page(title, "".join(parts)))
    return path
