"""`kintsugi explain`: a trial record told as one timeline, the same way for every system.

Skills (peg contact formations, tabletop actions, contact stages) with their real outcome, events
(monitors firing, recoveries, stages, restarts, disturbances, errors) and reasoning calls (role,
latency, a one-line gist of the reply) are merged on the trial's one sim-time clock and printed in
time order; then the record's typed sections (`task_figures`, `method_figures`) as key/value lines
and the outcome: ground truth against the method's verdict. `full=True` adds every call's request
and reply and the figures' long texts (cost code).

Everything printed comes from a record (model replies, names, errors), so all of it goes out as
plain `Text`: a reply holding `[/INST]` is shown as written, never parsed as Rich markup. Long lines
wrap at the console's width; nothing is cropped.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError
from rich.console import Console
from rich.table import Table
from rich.text import Text

from kintsugi.core.errors import KintsugiError
from kintsugi.core.record import SkillLog, TrialRecord

PLANNING_ROLES = frozenset({"composer", "arranger", "priors", "formulate"})
"""Roles a method asks before the robot first moves (a re-plan asks the composer again later)."""
CHECK_ROLES = ("judge", "analyze", "plan")
"""The peg recovery's roles: a judge call checks one skill; analyze and plan follow a failed check."""

STAGE_ENDS = ("stage done", "stage failed")
"""Contact stages log their end twice, as a skill and as an event: the timeline shows the skill."""

Key = tuple[float, float, int, int, int]


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


@dataclass
class Entry:
    """One line of the timeline: a skill, an event or a reasoning call, at sim time `t`.

    `key` orders entries (time first, then what happened first at equal times); `inferred` marks a
    call whose time the record does not hold (see `call_keys`)."""

    key: Key
    kind: str  # "skill", "event" or "call"
    text: str
    call: dict[str, Any] | None = None
    inferred: bool = False
    wall_s: float | None = None
    """Wall-clock seconds since the trial started, where the record holds them."""

    @property
    def t(self) -> float:
        return self.key[0]


def skill_end_times(rec: TrialRecord) -> list[float]:
    """Each skill's absolute end time (`SkillLog.sim_time`). Peg records written before the field was
    absolute hold each skill's duration: their times go back somewhere, so they are summed instead."""
    times = [s.sim_time for s in rec.skills]
    if any(b < a for a, b in zip(times, times[1:])):
        total, out = 0.0, []
        for d in times:
            total += d
            out.append(round(total, 4))
        return out
    return times


def call_keys(rec: TrialRecord, skills: list[Key], events: list[Key]) -> list[tuple[Key, bool]]:
    """Where each transcript call goes on the timeline, and whether its time is inferred.

    The transcript keeps calls in the order they were made but, unless a call carries its own
    `t` (or `sim_time`), not when. Each call is placed by the first rule that fits:

    1. its own time;
    2. a peg check (judge) at the end of the checked skill it judged (the n-th judge, the n-th skill
       with a verdict), right after that skill; analyze and plan calls after their judge;
    3. CoRAL's n-th `adapt` call just before the n-th `restart` event (the log entry that follows it);
       a re-plan's composer call (every composer call after the first) just after its `replan` event;
    4. planning calls (composer, arranger, priors, formulate) made before any other call: at the start;
       a failed call no rule above placed: just before the trial's `error` event (it ended the trial);
    5. any other call (e.g. a re-planner's verify calls) right after the nearest placed call before
       it, or at the start when none is: a lower bound, marked inferred.
    """
    calls = rec.transcript
    checked = [k for k, s in zip(skills, rec.skills) if s.verdict is not None]
    restarts = [k for k, e in zip(events, rec.events) if e.kind == "restart"]
    replans = [k for k, e in zip(events, rec.events) if e.kind == "replan"]
    errors = [k for k, e in zip(events, rec.events) if e.kind == "error"]
    out: list[tuple[Key, bool] | None] = []
    judged = adapted = composed = 0
    judge_key: Key | None = None
    leading = True
    for j, call in enumerate(calls):
        role = call.get("role")
        own = call.get("t", call.get("sim_time"))
        leading = leading and role in PLANNING_ROLES
        key: Key | None = None
        if isinstance(own, (int, float)) and not isinstance(own, bool):
            key = (float(own), 1.5, 0, 0, j)
        elif role == "judge" and judged < len(checked):
            judge_key = checked[judged][:3] + (1, j)
            key = judge_key
        elif role in CHECK_ROLES[1:] and judge_key is not None:
            key = judge_key[:4] + (j,)
        elif role == "adapt" and adapted < len(restarts):
            key = restarts[adapted][:3] + (-1, j)
        elif role == "composer" and 0 < composed <= len(replans):
            key = replans[composed - 1][:3] + (1, j)
        elif leading:
            key = (0.0, 0, 0, 0, j)
        elif call.get("error") and errors:  # the failed call ended the trial: just before its error event
            key = errors[0][:3] + (-1, j)
        judged += role == "judge"
        adapted += role == "adapt"
        composed += role == "composer"
        out.append(None if key is None else (key, False))
    for j, placed in enumerate(out):
        if placed is None:
            before = next((p[0] for p in reversed(out[:j]) if p is not None), None)
            out[j] = ((before[:4] + (j,)) if before is not None else (0.0, 0, 0, 0, j), True)
    return [p for p in out if p is not None]


def timeline(rec: TrialRecord) -> list[Entry]:
    """The record's skills, events and reasoning calls as one list in time order."""
    skills = [(t, 1, i, 0, 0) for i, t in enumerate(skill_end_times(rec))]
    events = [(e.t, 2, k, 0, 0) for k, e in enumerate(rec.events)]
    ends = {(round(t, 4), s.skill) for t, s in zip(skill_end_times(rec), rec.skills)}
    entries = [Entry(key, "event", f"{e.kind}: {e.detail}" if e.detail else e.kind, wall_s=e.wall_s)
               for key, e in zip(events, rec.events)
               if not (e.kind in STAGE_ENDS and (round(e.t, 4), e.detail) in ends)]  # the skill line says it
    told = set()  # a judge's explanation is the checked skill's message: tell it once, on the call
    for (key, inferred), call in zip(call_keys(rec, skills, events), rec.transcript):
        entries.append(Entry(key, "call", _call_text(call), call=call, inferred=inferred))
        if call.get("role") == "judge" and isinstance(call.get("reply"), dict):
            told.add(call["reply"].get("explanation"))
    entries += [Entry(key, "skill", _skill_text(s, s.message not in told), wall_s=s.wall_s)
                for key, s in zip(skills, rec.skills)]
    entries.sort(key=lambda e: e.key)
    return entries


def _wall(seconds: float | None) -> str:
    return "" if seconds is None else f" [wall {seconds:.2f} s]"


def outcome(s: SkillLog) -> str:
    """How a skill ended: reached, or why not (compression limit, timeout, or the robot's own message:
    IK unreachable, interrupted by a monitor, not settled, ...)."""
    if s.reached:
        return "reached"
    reason = "compression limit" if s.compression_limit else "timed out" if s.timed_out else "not reached"
    return f"{reason}: {s.message}" if s.message and s.verdict is None else reason


def _skill_text(s: SkillLog, message: bool = True) -> str:
    goal = " ".join(f"{k}={v:g}" for k, v in s.goal.items())
    text = f"{'recovery ' if s.recovery else ''}{s.skill}{' ' + goal if goal else ''} -> {outcome(s)}"
    if s.verdict is not None:
        text += f", verdict {'SUCCESS' if s.verdict else 'FAILURE'}"
    if message and s.message and (s.reached or s.verdict is not None):
        text += f" ({s.message})"
    return text


def gist(call: dict[str, Any]) -> str:
    """One line saying what a reasoning call answered (the reply's verdict, explanation, plan, or the
    size of what it produced), or its error."""
    reply = call.get("reply")
    if not isinstance(reply, dict):
        return f"error: {call.get('error') or 'no reply'}"
    parts: list[str] = []
    if isinstance(reply.get("success"), bool):
        parts.append("success" if reply["success"] else "failure")
    for name in ("explanation", "diagnosis", "what_happened", "why", "how_to_recover"):
        if isinstance(reply.get(name), str) and reply[name]:
            parts.append(reply[name] if name in ("explanation", "diagnosis", "what_happened")
                         else f"{name.replace('_', ' ')}: {reply[name]}")
    if isinstance(reply.get("steps"), list):
        parts.append("plan " + ", ".join(
            f"{s.get('skill')} " + " ".join(f"{a}={v:g}" for a, v in (s.get("goal") or {}).items())
            for s in reply["steps"] if isinstance(s, dict)))
    graph = reply.get("graph")
    if isinstance(graph, dict):
        parts.append(f"graph of {len(graph.get('nodes') or [])} nodes, {len(graph.get('edges') or [])} edges")
    for name in ("proposals", "stages", "regions", "motions"):
        if isinstance(reply.get(name), list) and reply[name]:
            parts.append(f"{len(reply[name])} {name}")
    if isinstance(reply.get("source"), str):
        parts.append(f"cost code of {len(reply['source'].splitlines())} lines")
    if isinstance(reply.get("objects"), dict):
        parts.append("; ".join(f"{k} " + ", ".join(f"{a}={v}" for a, v in o.items())
                               for k, o in reply["objects"].items() if isinstance(o, dict)))
    if isinstance(reply.get("reasoning"), str) and reply["reasoning"]:
        parts.append(reply["reasoning"])
    return "; ".join(parts) or json.dumps(reply)[:200]


def _call_text(call: dict[str, Any]) -> str:
    cost = [str(call.get("backend", "?")), f"{call.get('latency_s', 0.0):.3f} s"]
    if call.get("tokens_in") or call.get("tokens_out"):
        cost.append(f"{call.get('tokens_in', 0)}+{call.get('tokens_out', 0)} tokens")
    if call.get("attempts", 1) != 1:
        cost.append(f"{call['attempts']} attempts")
    return f"{call.get('role', '?')} ({', '.join(cost)}): {gist(call)}"


def _rows(entries: list[Entry]) -> list[tuple[str, str, Entry, int]]:
    """(time, label, entry, repeats): consecutive identical skills (e.g. an open gripper held) fold into
    one row with their time span."""
    rows: list[tuple[str, str, Entry, int]] = []
    first_t = 0.0
    for e in entries:
        last = rows[-1] if rows else None
        if last and e.kind == "skill" and last[2].kind == "skill" and last[2].text == e.text:
            rows[-1] = (f"{first_t:.2f}-{e.t:.2f} s", last[1], e, last[3] + 1)
            continue
        first_t = e.t
        label = {"skill": "skill", "event": "event", "call": "reason"}[e.kind]
        rows.append((f"{'>=' if e.inferred else ''}{e.t:.2f} s", label, e, 1))
    return rows


def explain_record(rec: TrialRecord, console: Console, full: bool = False) -> None:
    """Print the record's timeline, its figures and its outcome; `full` adds each call's request and
    reply and the figures' long texts. A time marked `>=` is a lower bound: a call placed by `call_keys`
    rule 5, made at or after it."""
    console.rule()
    console.print(Text(rec.key, style="bold"), soft_wrap=False)  # a rule's title would be cropped
    _print_pairs(console, "hidden truth", rec.params, full)
    grid = Table.grid(padding=(0, 1))
    grid.add_column(justify="right", no_wrap=True, style="dim")
    grid.add_column(no_wrap=True)
    grid.add_column(overflow="fold")
    for when, label, e, n in _rows(timeline(rec)):
        text = Text(e.text + (f" (x{n})" if n > 1 else "") + _wall(e.wall_s), style="bold" if e.kind == "skill" else "")
        if full and e.call is not None:
            text.append("\n" + json.dumps({k: e.call.get(k) for k in ("request", "reply", "error")}, indent=1),
                        style="")
        grid.add_row(when, label, text)
    console.print(grid, soft_wrap=False)
    _print_pairs(console, "task figures", rec.task_figures, full)
    _print_pairs(console, "method figures", rec.method_figures, full)
    if rec.video:
        console.print(Text(f"video: {rec.video}"), soft_wrap=False)
    head = Text(f"ground truth {'SUCCESS' if rec.success else 'FAILURE'}", style="bold green" if rec.success
                else "bold red")
    head.append(f", method's verdict {'success' if rec.framework_success else 'failure'}", style="bold")
    if rec.error:
        head.append(f", error: {rec.error}", style="red")
    calls = rec.transcript  # counted as the runner counts them
    head.append(f"; sim {rec.sim_time:.2f} s, wall {rec.wall_time:.2f} s, {rec.physics_steps} physics steps, "
                f"{len(calls)} reasoning calls ({sum(c.get('latency_s', 0.0) for c in calls):.3f} s, "
                f"{sum(1 for c in calls if c.get('error'))} errors)")
    console.print(head, soft_wrap=False)


def _flat(value: Any, prefix: str, full: bool) -> list[tuple[str, str]]:
    """Dotted key/value pairs of a JSON value; multi-line texts (cost code) only with `full`."""
    if isinstance(value, dict):
        return [p for k, v in value.items() if v is not None for p in _flat(v, f"{prefix}.{k}" if prefix else k, full)]
    if isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        return [p for i, v in enumerate(value) for p in _flat(v, f"{prefix}[{i}]", full)]
    if isinstance(value, str) and "\n" in value and not full:
        return [(prefix, f"<{len(value.splitlines())} lines; --full shows them>")]
    if isinstance(value, float):
        return [(prefix, f"{value:.6g}")]
    return [(prefix, value if isinstance(value, str) else json.dumps(value))]


def _print_pairs(console: Console, title: str, data: dict[str, Any], full: bool) -> None:
    """A section as `key=value` pairs: the top-level scalars on one wrapped line, then one line per
    nested part (`priors: box.mass_kg=... box.friction=...`, `attempts[0]: ...`)."""
    groups: dict[str, list[str]] = {}
    for key, value in _flat(data, "", full):
        head, dot, rest = key.partition(".")
        if not dot and "[" in head:  # an item of a list of lists
            head, rest = head.split("[", 1)[0], key
        groups.setdefault(head if dot or rest else "", []).append(f"{rest or key}={value}")
    if not groups:
        return
    grid = Table.grid(padding=(0, 1))
    grid.add_column(no_wrap=True, style="bold")
    grid.add_column(overflow="fold")
    for i, (head, pairs) in enumerate(sorted(groups.items(), key=lambda g: g[0] != "")):
        text = Text(f"{head}: " if head else "", style="dim")
        text.append(("\n" if any("\n" in p for p in pairs) else "  ").join(pairs), style="")
        grid.add_row(title if i == 0 else "", text)
    console.print(grid, soft_wrap=False)
