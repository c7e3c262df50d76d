"""`kintsugi explain`: one timeline in sim-time order for every system, real outcomes, nothing cropped.

Records of the three systems are built directly (small and exact); one real peg trial comes from
`run_trial` (about two seconds). Everything printed comes from records, so markup-like text must
be shown verbatim.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from rich.console import Console
from typer.testing import CliRunner

from kintsugi.cli import app
from kintsugi.cli.explain import explain_record, load_record, skill_end_times, timeline
from kintsugi.core.record import Event, SkillLog, TrialRecord, TrialSpec

MARKUP = "[/INST] [bold]not bold[/x]"
LONG = " ".join(f"word{i:02d}" for i in range(60))


def invoke(*args: object):  # noqa: ANN201
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert "Traceback" not in result.output, result.output
    return result


def flat(text: str) -> str:
    """Console output with line breaks and alignment folded to single spaces (wrapping moves them)."""
    return " ".join(text.split())


def render(rec: TrialRecord, width: int = 160, full: bool = False) -> str:
    console = Console(record=True, width=width)
    explain_record(rec, console, full=full)
    return console.export_text()


def call(role: str, reply: dict | None, **extra: object) -> dict:
    return {"role": role, "backend": "embedded", "request": {"task": f"request of {role}"}, "reply": reply,
            "error": None, "latency_s": 0.01, "tokens_in": 0, "tokens_out": 0, "attempts": 1, **extra}


def skill(name: str, t: float, reached: bool = True, **extra: object) -> SkillLog:
    return SkillLog(skill=name, goal=extra.pop("goal", {}), terminal={}, reached=reached, sim_time=t, **extra)


def record(key: str, **fields: object) -> TrialRecord:
    task, method, variant, condition, seed = key.split("/")
    return TrialRecord(key=key, task=task, method=method, variant=variant, condition=condition, seed=int(seed),
                       **fields)


def peg_record() -> TrialRecord:
    """System A: the fit fails its check, analyze and plan follow, the plan is clamped, the recovery fit passes."""
    return record(
        "peg-insertion/recovery/square/all/0", params={"hole_y_mm": 3.2}, success=True, framework_success=True,
        skills=[skill("approach", 0.62, goal={"y": -64.5}), skill("contact", 1.344),
                skill("fit", 3.192, verdict=False, message="Fit failed: tip on the board"),
                skill("fit", 3.628, recovery=True, verdict=True, message="Fit succeeded: tip in the hole")],
        events=[Event(t=3.192, kind="plan-clamped", detail="step 1 (fit): y 40 -> 10")],
        transcript=[call("judge", {"success": False, "explanation": "Fit failed: tip on the board"}),
                    call("analyze", {"what_happened": "tip beside the hole", "why": "hole moved",
                                     "how_to_recover": "fit again", "restart_from": "fit", "motions": []}),
                    call("plan", {"steps": [{"skill": "fit", "goal": {"y": 10.0}}]}),
                    call("judge", {"success": True, "explanation": "Fit succeeded: tip in the hole"})],
        sim_time=3.628, task_figures={}, method_figures={"extra_executions": {"fit": 1}})


def tabletop_record() -> TrialRecord:
    """System B: compile calls, a drop caught by a monitor, an IK failure and an interrupted action."""
    return record(
        "pour-single/agentchord/default/drop/1", params={"bottle_x": 0.39}, success=False,
        skills=[skill("grasp", 4.15, message="pose error 0.4 mm, 0.0 deg"),
                skill("move_to_obj", 5.0, reached=False, message="IK unreachable: the cup is 0.9 m away"),
                skill("rotate_eef", 7.63, reached=False,
                      message="interrupted by a step observer after 39 control steps"),
                skill("open_gripper", 7.76, recovery=True), skill("open_gripper", 7.85, recovery=True)],
        events=[Event(t=0.0, kind="compiled", detail="47 nodes, 67 edges"),
                Event(t=7.6, kind="disturbance", detail="right gripper dropped bottle"),
                Event(t=7.63, kind="monitor", detail="m.e5.drop fired -> recovery re.e5.0")],
        transcript=[call("composer", {"graph": {"nodes": [{}, {}], "edges": [{}]}, "reasoning": "two steps"}),
                    call("arranger", {"proposals": [{}], "reasoning": "one branch"})],
        sim_time=7.85, task_figures={"poured": False, "max_tilt_deg": 12.5},
        method_figures={"episode_steps": 785, "recovery_latency_steps": [3]},
        error="ConductorError: ran out of actions")


def contact_record() -> TrialRecord:
    """System C: the first attempt's tip stage times out, the adaptation runs, the scene restarts."""
    return record(
        "flip-box/coral/default/all/0", params={"box.mass_kg": 0.1},
        skills=[skill("approach", 0.9), skill("tip", 3.0, reached=False, timed_out=True),
                skill("approach", 3.8), skill("tip", 4.4)],
        events=[Event(t=0.0, kind="stage", detail="approach timeout_s=4"),
                Event(t=0.9, kind="stage done", detail="approach"),
                Event(t=3.0, kind="stage failed", detail="tip"),
                Event(t=3.0, kind="restart", detail="attempt 2 of 3")],
        transcript=[call("priors", {"objects": {"box": {"mass_kg": 0.06}}, "reasoning": "cardboard"}),
                    call("formulate", {"source": "def a():\n    return 1\n", "stages": [{}], "reasoning": "push"}),
                    call("adapt", {"diagnosis": "the box is heavier than believed"})],
        sim_time=4.4, method_figures={"attempts": [{"attempt": 1, "source": "def a():\n    return 1\n"}]})


def positions(text: str, *needles: str) -> list[int]:
    out = flat(text)
    for n in needles:
        assert n in out, n
    return [out.index(n) for n in needles]


@pytest.mark.parametrize("make", [peg_record, tabletop_record, contact_record])
def test_every_system_explains_in_time_order(make) -> None:  # noqa: ANN001
    rec = make()
    entries = timeline(rec)
    assert [e.t for e in entries] == sorted(e.t for e in entries)
    assert sum(e.kind == "call" for e in entries) == len(rec.transcript)
    text = render(rec)
    outcome = "ground truth SUCCESS" if rec.success else "ground truth FAILURE"
    assert flat(text).rindex(outcome) > max(positions(text, *(s.skill for s in rec.skills)))


def test_peg_checks_follow_the_skill_they_judged() -> None:
    order = positions(render(peg_record()), "contact -> reached", "fit -> reached, verdict FAILURE",
                      "judge (embedded", "analyze (embedded", "plan (embedded, 0.010 s): plan fit y=10",
                      "plan-clamped: step 1", "recovery fit -> reached, verdict SUCCESS",
                      "judge (embedded, 0.010 s): success; Fit succeeded", "method's verdict success")
    assert order == sorted(order)
    assert flat(render(peg_record())).count("Fit failed: tip on the board") == 1  # told once, on the judge call


def test_tabletop_events_and_actions_merge_and_unfinished_actions_say_why() -> None:
    text = render(tabletop_record())
    order = positions(text, "composer (embedded", "arranger (embedded", "compiled: 47 nodes", "grasp -> reached",
                      "move_to_obj -> not reached: IK unreachable: the cup is 0.9 m away",
                      "disturbance: right gripper dropped bottle",
                      "rotate_eef -> not reached: interrupted by a step observer after 39 control steps",
                      "monitor: m.e5.drop fired", "7.76-7.85 s skill recovery open_gripper -> reached (x2)",
                      "task figures poured=false max_tilt_deg=12.5",
                      "error: ConductorError: ran out of actions")
    assert order == sorted(order)
    assert "timeout" not in text and "timed out" not in text


def test_contact_stages_restart_and_adaptation() -> None:
    text = render(contact_record())
    order = positions(text, "priors (embedded", "formulate (embedded", "stage: approach", "approach -> reached",
                      "tip -> timed out", "adapt (embedded, 0.010 s): the box is heavier than believed",
                      "restart: attempt 2 of 3", "tip -> reached", "attempts[0]: attempt=1 source=<2 lines")
    assert order == sorted(order)
    assert "stage done" not in text and "stage failed" not in text  # the skill lines say it


def test_long_lines_wrap_instead_of_being_cropped() -> None:
    rec = tabletop_record()
    skills, events, calls = list(rec.skills), list(rec.events), list(rec.transcript)
    skills[1] = skills[1].model_copy(update={"message": LONG})
    events[1] = events[1].model_copy(update={"detail": LONG.upper()})
    calls[0] = call("composer", {"reasoning": LONG.replace("word", "why")})
    rec = rec.model_copy(update={"skills": skills, "events": events, "transcript": calls,
                                 "params": {"note": LONG.replace("word", "p")}, "error": LONG.replace("word", "e")})
    text = render(rec, width=40)
    assert max(len(line) for line in text.splitlines()) <= 40
    out = flat(text)
    assert "pour-single/agentchord/default/drop/1" in out  # the title too
    for long in (LONG, LONG.upper(), LONG.replace("word", "why"), LONG.replace("word", "p"), LONG.replace("word", "e")):
        for word in long.split():
            assert re.search(rf"(?<!\w){word}(?!\w)", out), word


def test_full_shows_each_call_request_and_reply(tmp_path: Path) -> None:
    path = tmp_path / "r.json"
    path.write_text(contact_record().model_dump_json())
    short, full = invoke("explain", path), invoke("explain", path, "--full")
    assert short.exit_code == full.exit_code == 0, short.output + full.output
    assert "request of adapt" not in short.output and "return 1" not in short.output
    assert "request of adapt" in full.output and '"diagnosis": "the box is heavier than believed"' in full.output
    assert "    return 1" in full.output  # the cost code, as written


def test_a_real_peg_trial_explains_in_time_order() -> None:
    from kintsugi.core.runner import run_trial

    rec = run_trial(TrialSpec(task="peg-insertion", method="recovery", variant="round", condition="all", seed=3))
    assert rec.error is None and rec.transitions
    times = [s.sim_time for s in rec.skills]
    assert times == sorted(times) and times[-1] == pytest.approx(rec.sim_time)  # absolute end times
    entries = timeline(rec)
    assert [e.t for e in entries] == sorted(e.t for e in entries)
    for i, e in enumerate(entries):
        if e.kind == "skill" and "verdict" in e.text:
            assert entries[i + 1].text.startswith("judge ")
    order = positions(render(rec), "fit y=1.5 -> reached, verdict SUCCESS", "align y=-1 -> reached, verdict FAILURE",
                      "analyze (embedded", "plan (embedded", "recovery align", "recovery insert")
    assert order == sorted(order)


def test_records_holding_skill_durations_are_summed() -> None:
    """Peg records written while SkillLog.sim_time was a duration still tell the right times."""
    rec = peg_record()
    old = rec.model_copy(update={"skills": [s.model_copy(update={"sim_time": d})
                                            for s, d in zip(rec.skills, (0.62, 0.724, 1.848, 0.436))]})
    assert skill_end_times(old) == pytest.approx([s.sim_time for s in rec.skills])
    assert skill_end_times(rec) == [s.sim_time for s in rec.skills]


def test_unplaced_calls_follow_the_last_placed_one() -> None:
    """A re-planner's verify calls carry no time: after the call placed before them, marked as a lower bound."""
    rec = tabletop_record()
    rec = rec.model_copy(update={
        "events": [*rec.events, Event(t=7.9, kind="replan", detail="asking the composer again")],
        "transcript": [*rec.transcript, call("verify", {"success": False, "explanation": "not held"}),
                       call("composer", {"graph": {"nodes": [], "edges": []}}),
                       call("verify", {"success": True, "explanation": "held again"}),
                       call("judge", {"success": True, "explanation": "checked at 8.5"}, t=8.5)]})
    text = render(rec)
    order = positions(text, ">=0.00 s reason verify", "7.90 s event replan", "7.90 s reason composer",
                      ">=7.90 s reason verify", "8.50 s reason judge")
    assert order == sorted(order)


# ----- the command ------------------------------------------------------------------------------

def markup_record() -> TrialRecord:
    markup_call = call("judge", {"success": False, "explanation": MARKUP}, backend=MARKUP)
    return record(
        "peg-insertion/recovery/square/all/0", params={"note": MARKUP},
        skills=[skill("approach", 0.5, goal={"y": 1.0}),
                skill("fit", 1.5, verdict=False, message=MARKUP, goal={"y": 2.0}),
                skill("fit", 2.5, recovery=True, verdict=True, goal={"y": 3.0})],
        events=[Event(t=1.5, kind="plan-clamped", detail=f"step 1 {MARKUP}"), Event(t=2.5, kind="[bold]", detail=MARKUP)],
        transcript=[markup_call, {**markup_call, "role": "analyze"}, {**markup_call, "role": "plan"},
                    {**markup_call, "reply": None, "error": MARKUP}],
        error=f"ReasoningError: {MARKUP}")


def test_explain_prints_markup_like_text_in_every_field(tmp_path: Path) -> None:
    path = tmp_path / "r.json"
    path.write_text(markup_record().model_dump_json())
    res = invoke("explain", path)
    assert res.exit_code == 0, res.output
    out = flat(res.output)
    for text in (f"note={MARKUP}", f"judge ({MARKUP}, 0.010 s): failure; {MARKUP}", f"error: {MARKUP}",
                 f"plan-clamped: step 1 {MARKUP}", f"2.50 s event [bold]: {MARKUP}", f"error: ReasoningError: {MARKUP}"):
        assert text in out, text
    # The clamp happened after the first fit's reasoning, before the recovery fit ran.
    assert out.index("plan (") < out.index("plan-clamped") < out.index("recovery fit")


def test_explain_key_accepts_both_forms_and_bad_files_are_one_line_errors(tmp_path: Path) -> None:
    rec = markup_record()
    other = rec.model_copy(update={"key": "peg-insertion/recovery/square/all/1", "seed": 1})
    results = tmp_path / "results.jsonl"
    results.write_text(rec.model_dump_json() + "\n" + other.model_dump_json() + "\n")
    for key in ("peg-insertion/recovery/square/all/1", "peg-insertion__recovery__square__all__1"):
        res = invoke("explain", results, "--key", key)
        assert res.exit_code == 0 and "peg-insertion/recovery/square/all/1" in res.output
        assert load_record(results, key).seed == 1
    assert invoke("explain", tmp_path, "--key", "peg-insertion__recovery__square__all__0").exit_code == 0
    res = invoke("explain", results)
    assert res.exit_code == 2 and "holds 2 records" in res.stderr
    (tmp_path / "bad.json").write_text("{not json")
    for path in (tmp_path / "bad.json", tmp_path / "missing.json"):
        res = invoke("explain", path)
        assert res.exit_code == 2 and res.stderr.startswith("error:")


def test_a_failed_call_sits_before_the_error_it_caused() -> None:
    rec = peg_record()
    rec = rec.model_copy(update={
        "skills": [*rec.skills, skill("align", 4.0)],
        "events": [*rec.events, Event(t=4.0, kind="error", detail="ReasoningError: endpoint gone")],
        "transcript": [*rec.transcript, call("judge", None, error="ReasoningError: endpoint gone")]})
    order = positions(render(rec), "4.00 s skill align -> reached", "4.00 s reason judge (embedded, 0.010 s): error:",
                      "4.00 s event error: ReasoningError")
    assert order == sorted(order)


def test_json_prints_the_raw_record_and_verbose_is_full(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from kintsugi.cli import app
    from kintsugi.core.record import TrialRecord

    rec = TrialRecord(key="t/m/v/c/0", task="t", method="m", variant="v", condition="c", seed=0, success=True,
                      transcript=[{"role": "judge", "backend": "embedded", "request": {"q": "secret-request"},
                                   "reply": {"success": True}, "latency_s": 0.01}])
    path = tmp_path / "r.json"
    path.write_text(rec.model_dump_json())
    raw = CliRunner().invoke(app, ["explain", str(path), "--json"])
    assert TrialRecord.model_validate_json(raw.output) == rec
    plain = CliRunner().invoke(app, ["explain", str(path)]).output
    verbose = CliRunner().invoke(app, ["explain", str(path), "--verbose"]).output
    assert "secret-request" not in plain and "secret-request" in verbose
