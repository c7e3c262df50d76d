"""`kintsugi explain`: a trial record told as a story, with the reasoning transcript.

Everything printed comes from a record (model replies, names, errors), so all of it is
escaped: a reply holding `[/INST]` is shown as written, never parsed as Rich markup.
"""

from __future__ import annotations

import json
from pathlib import Path

from pydantic import ValidationError
from rich.console import Console
from rich.markup import escape
from rich.panel import Panel
from rich.text import Text

from kintsugi.core.errors import KintsugiError
from kintsugi.core.record import Event, TrialRecord

_SAME_TIME_S = 1e-3  # skill durations are rounded to 0.1 ms; their sums drift a little


def load_record(path: Path, key: str | None = None) -> TrialRecord:
    """One record from a .json file, or the one with `key` (or the only one) from a .jsonl file or a campaign dir.

    `key` may be written with `/` (as in records) or `__` (as in record and video file names).
    """
    if path.is_dir():
        path = path / "results.jsonl"
    try:
        text = path.read_text()
    except OSError as exc:
        raise KintsugiError(f"cannot read {path}: {exc.strerror or exc}") from None
    try:
        if path.suffix == ".jsonl":
            recs = [TrialRecord.model_validate_json(line) for line in text.splitlines() if line.strip()]
        else:
            recs = [TrialRecord.model_validate_json(text)]
    except ValidationError as exc:
        raise KintsugiError(f"{path} is not a kintsugi trial record: {exc.errors()[0]['msg']}") from None
    if key is not None:
        recs = [r for r in recs if key in (r.key, r.key.replace("/", "__"))]
    if len(recs) != 1:
        raise KintsugiError(f"{path} holds {len(recs)} records matching {key!r}; "
                            "pass --key task/method/variant/condition/seed")
    return recs[0]


def _print_call(call: dict, console: Console) -> None:
    body = json.dumps(call.get("reply"), indent=1) if call.get("reply") else f"error: {call.get('error', '')}"
    title = (f"{call.get('role', '?')} ({call.get('backend', '?')}, {call.get('latency_s', 0):.3f} s, "
             f"{call.get('tokens_in', 0)}+{call.get('tokens_out', 0)} tokens)")
    console.print(Panel(Text(body), title=escape(title)))


def _print_event(e: Event, console: Console) -> None:
    console.print(Text(f"event {e.t:.2f}s {e.kind}: {e.detail}"))


def explain_record(rec: TrialRecord, console: Console) -> None:
    """Skills in order, each checked one followed by its judge/analyze/plan calls, and events
    (plan clamps, timeouts, errors) where they happened: after the skill that ended at or after their time.

    A skill's `sim_time` is its duration; skills run back to back from t = 0, so their running sum is
    the time each one ended.
    """
    console.rule(f"[bold]{escape(rec.key)}[/bold]")
    console.print(Text(f"hidden truth: {json.dumps(rec.params)}"))
    calls = list(rec.transcript)
    events = sorted(rec.events, key=lambda e: e.t)  # stable: same-time events keep their order
    t_end = 0.0
    for s in rec.skills:
        t_end += s.sim_time
        verdict = "" if s.verdict is None else (" -> [green]success[/green]" if s.verdict else " -> [red]failure[/red]")
        flags = "reached" if s.reached else ("compression limit" if s.compression_limit else "timeout")
        console.print(f"[bold]{escape(s.skill)}[/bold]{' (recovery)' if s.recovery else ''} "
                      f"goal {escape(str(s.goal))} -> {flags}{verdict}")
        if s.verdict is not None:
            # A checked skill owns one judge call and, on failure, the analyze/plan calls that follow it.
            while calls:
                _print_call(calls.pop(0), console)
                if not calls or calls[0].get("role") == "judge":
                    break
        while events and events[0].t <= t_end + _SAME_TIME_S:
            _print_event(events.pop(0), console)
    for call in calls:  # calls that no skill claimed (e.g. the trial ended in a reasoning error)
        _print_call(call, console)
    for e in events:
        _print_event(e, console)
    _print_coral(rec, console)
    verdict = "SUCCESS" if rec.success else "FAILURE"
    console.print(f"[bold]ground truth {verdict}[/bold], framework {'success' if rec.framework_success else 'failure'}"
                  + escape(f", error: {rec.error}" if rec.error else ""))


def _beliefs(b: dict | None) -> str:
    if not b:
        return "-"
    return ", ".join(f"{k} {v.get('mass_kg', float('nan')):.4g} kg / friction {v.get('friction', float('nan')):.3g}"
                     for k, v in b.items())


def _print_coral(rec: TrialRecord, console: Console) -> None:
    """CoRAL's attempts (details.method.attempts): priors, the cost code and contact regions each attempt ran,
    the adaptation's reasoning and the beliefs before and after it. Model-written code is shown as text."""
    method = rec.details.get("method") if isinstance(rec.details, dict) else None
    if not isinstance(method, dict) or not isinstance(method.get("attempts"), list):
        return
    console.rule("[bold]CoRAL attempts[/bold]")
    console.print(Text(f"priors (role priors): {_beliefs(method.get('priors'))}"))
    console.print(Text(f"plan from: {method.get('plan_from', '?')}"
                       + (f"; memory {json.dumps(method['memory'])}" if method.get("memory") else "")))
    previous = None
    for a in method["attempts"]:
        if not isinstance(a, dict):
            continue
        head = (f"attempt {a.get('attempt')}: {'reached' if a.get('reached') else 'failed'}"
                f"; beliefs {_beliefs(a.get('beliefs_before'))}"
                f"; cost code {a.get('code_ms_per_step', '?')} ms per planning step of "
                f"{a.get('mppi_ms_per_step', '?')} ms")
        console.print(Text(head, style="bold"))
        stages = a.get("stages") or []
        console.print(Text("stages: " + " -> ".join(
            f"{s.get('name')}[cost={s.get('cost')}, done={s.get('done')}, grip={s.get('grip')}"
            + (f", region={s.get('region')}" if s.get("region") is not None else "")
            + (f", press={s.get('press_n')} N" if s.get("press_n") is not None else "") + "]" for s in stages)))
        for i, r in enumerate(a.get("regions") or []):
            console.print(Text(f"region {i}: {r.get('object')} centre {r.get('center')} normal {r.get('normal')} "
                               f"radius {r.get('radius')} m"))
        source = a.get("source") or ""
        if source != previous:
            console.print(Panel(Text(source), title=f"cost code (attempt {a.get('attempt')})"))
        else:
            console.print(Text("cost code: unchanged"))
        previous = source
        if a.get("cost_error"):
            console.print(Text(f"cost code error: {a['cost_error']}", style="red"))
        if a.get("sysid"):
            s = a["sysid"]
            console.print(Text(f"sysid: {s.get('object')} {s.get('mass_kg', 0):.4g} kg, friction {s.get('friction', 0):.3g}"
                               f" over {s.get('windows')} windows (loss {s.get('loss_prior', 0):.3g} -> "
                               f"{s.get('loss_fit', 0):.3g})"))
        if a.get("adaptation"):
            console.print(Panel(Text(str(a["adaptation"])), title="adaptation (role adapt)"))
            if a.get("adaptation_notes"):
                console.print(Text("checks: " + "; ".join(map(str, a["adaptation_notes"]))))
            if a.get("beliefs_after"):
                console.print(Text(f"beliefs {_beliefs(a.get('beliefs_before'))} -> {_beliefs(a.get('beliefs_after'))}"))
