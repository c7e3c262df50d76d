"""`kintsugi explain`: a trial record told as a story, with the reasoning transcript."""

from __future__ import annotations

import json
from pathlib import Path

from pydantic import ValidationError
from rich.console import Console
from rich.panel import Panel

from kintsugi.errors import KintsugiError
from kintsugi.trial import TrialRecord


def load_record(path: Path, key: str | None = None) -> TrialRecord:
    """One record from a .json file, or the one with `key` (or the only one) from a .jsonl file."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise KintsugiError(f"cannot read {path}: {exc}") from None
    try:
        if path.suffix == ".jsonl":
            recs = [TrialRecord.model_validate_json(line) for line in text.splitlines() if line.strip()]
            if key is not None:
                recs = [r for r in recs if r.key == key]
            if len(recs) != 1:
                raise KintsugiError(f"{path} holds {len(recs)} matching records; pass --key <task/method/...>")
            return recs[0]
        return TrialRecord.model_validate_json(text)
    except ValidationError as exc:
        raise KintsugiError(f"{path} is not a kintsugi trial record: {exc.errors()[0]['msg']}") from None


def _print_call(call: dict, console: Console) -> None:
    body = json.dumps(call.get("reply"), indent=1) if call.get("reply") else f"error: {call.get('error', '')}"
    console.print(Panel(body, title=f"{call['role']} ({call['backend']}, {call.get('latency_s', 0):.3f} s, "
                                    f"{call.get('tokens_in', 0)}+{call.get('tokens_out', 0)} tokens)"))


def explain_record(rec: TrialRecord, console: Console) -> None:
    console.rule(f"[bold]{rec.key}[/bold]")
    console.print(f"hidden truth: {json.dumps(rec.params)}")
    calls = list(rec.transcript)
    for s in rec.skills:
        verdict = "" if s.verdict is None else (" -> [green]success[/green]" if s.verdict else " -> [red]failure[/red]")
        flags = "reached" if s.reached else ("compression limit" if s.compression_limit else "timeout")
        console.print(f"[bold]{s.skill}[/bold]{' (recovery)' if s.recovery else ''} goal {s.goal} -> {flags}{verdict}")
        if s.verdict is None:
            continue
        # A checked skill owns one judge call and, on failure, the analyze/plan calls that follow it.
        while calls:
            _print_call(calls.pop(0), console)
            if not calls or calls[0]["role"] == "judge":
                break
    for call in calls:  # calls that no skill claimed (e.g. the trial ended in a reasoning error)
        _print_call(call, console)
    for e in rec.events:
        console.print(f"event {e.t:.2f}s {e.kind}: {e.detail}")
    verdict = "SUCCESS" if rec.success else "FAILURE"
    console.print(f"[bold]ground truth {verdict}[/bold], framework {'success' if rec.framework_success else 'failure'}"
                  f"{', error: ' + rec.error if rec.error else ''}")
