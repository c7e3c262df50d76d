"""Command line: run one trial, run a campaign, list what is registered, explain a trial."""

from __future__ import annotations

import traceback
from pathlib import Path
from typing import Annotated, Literal, Optional

import typer
from rich.markup import escape

from kintsugi.cli.app import app
from kintsugi.core.errors import KintsugiError
from kintsugi.cli.options import (  # noqa: F401 - _record_path is part of what tests and users import from here
    BaseUrlOpt, KeyEnvOpt, ModelOpt, PluginOpt, ReasonerOpt, SetOpt, StructuredOpt, _csv, _echo, _fail, _overrides,
    _plugins, _reasoner, _record_path, console, err_console, ConfigOpt,
)


@app.command()
def run(
    task: Annotated[str, typer.Argument(help="registered task, see `kintsugi tasks`")],
    method: Annotated[Optional[str], typer.Option(
        help="registered method, see `kintsugi methods` [default: the task's own system's method: "
             "recovery, agentchord or coral]")] = None,
    shape: Annotated[Optional[str], typer.Option(
        "--shape", "--variant", help="task variant, e.g. a peg shape [default: the task's first]")] = None,
    condition: Annotated[Optional[str], typer.Option(
        help="condition, see `kintsugi tasks` (e.g. none, pose, drop, all) [default: the task's first default "
             "condition, the one `kintsugi bench` runs first]")] = None,
    seed: Annotated[int, typer.Option(min=0, help="seed of the condition's random draws (the trial's hidden "
                                                  "truth: poses, frictions, masses, disturbances); the same "
                                                  "seed gives the same trial")] = 0,
    video: Annotated[Optional[Path], typer.Option(help="write an .mp4 or .gif of the scene camera")] = None,
    viewer: Annotated[bool, typer.Option("--viewer", help="watch in MuJoCo's passive viewer (needs a display; "
                                                          "over SSH see `kintsugi watch --live`)")] = False,
    record: Annotated[Optional[Path], typer.Option(
        help="trial record .json [default: runs/<task>__<method>__<variant>__<condition>__<seed>, then the "
             "reasoner when the trial asked it anything and a hash of any --config/--set values]")] = None,
    config_file: ConfigOpt = None,
    set_: SetOpt = None,
    reasoner: ReasonerOpt = "embedded",
    model: ModelOpt = None,
    base_url: BaseUrlOpt = None,
    api_key_env: KeyEnvOpt = "OPENAI_API_KEY",
    structured_output: StructuredOpt = "auto",
    plugin: PluginOpt = None,
) -> None:
    """Run one trial, tell its story skill by skill, and save its record (and video).

    Exits 1 when the trial recorded an error (e.g. an unreachable endpoint); the record is saved first.
    """
    plugin = _plugins(plugin)
    from kintsugi.campaign.plan import campaign_for, expand, task_defaults
    from kintsugi.campaign.runner import first_line
    from kintsugi.core.outputs import check_output_file
    from kintsugi.core.runner import failed_record, run_trial
    from kintsugi.core.video import check_video_path

    try:  # every name, setting and output path is checked before the trial spends anything
        one = [condition] if condition else [task_defaults(task, plugin)[2][0]]  # the first one bench runs
        cfg = campaign_for(task, [method] if method else None, [shape] if shape else None, one, trials=1,
                           base_seed=seed, overrides=_overrides(set_, config_file), plugins=plugin,
                           reasoner=_reasoner(reasoner, model, base_url, api_key_env, structured_output))
        spec = expand(cfg)[0].model_copy(update={"video": str(check_video_path(video)) if video else None})
        path = check_output_file(record or _record_path(spec), "record", (".json",))
        check_output_file(record or _record_path(spec, reasoned=False), "record", (".json",))
        from kintsugi.export.live import PassiveViewer
        from kintsugi.reasoning.preflight import preflight

        watcher = PassiveViewer() if viewer else None  # no display: a one-line error before the trial
        for note in preflight([spec]):  # stops here when the endpoint cannot serve the method's roles
            err_console.print(escape(f"preflight: {note}"))
    except KintsugiError as exc:
        _fail(exc)
        return
    console.rule(f"[bold]{escape(spec.key)}[/bold]")
    try:
        result = run_trial(spec, echo=_echo, attach=watcher.attach if watcher else None)
    except KintsugiError as exc:  # e.g. the video could not be encoded: keep what is known
        result = failed_record(spec, f"{type(exc).__name__}: {exc}")
    except Exception as exc:  # noqa: BLE001 - a bug in a task: record it with its traceback, do not crash
        result = failed_record(spec, f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=4)}")
    finally:
        if watcher is not None:
            watcher.finish()
    path = record or _record_path(spec, reasoned=result.reasoning_calls > 0)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(result.model_dump_json(indent=2))
    except OSError as exc:
        _fail(f"cannot write the record {path}: {exc}")
    colour = "green" if result.success else "red"
    console.print(f"[bold {colour}]ground truth: {'SUCCESS' if result.success else 'FAILURE'}[/bold {colour}]"
                  f"  framework verdict: {'success' if result.framework_success else 'failure'}"
                  f"  sim {result.sim_time:.2f} s, wall {result.wall_time:.2f} s, "
                  f"{result.reasoning_calls} reasoning calls")
    console.print(escape(f"record: {path}" + (f"   video: {result.video}" if result.video else "")))
    if result.error:
        _fail(f"the trial recorded an error: {first_line(result.error)}", code=1)


@app.command()
def bench(
    task: Annotated[str, typer.Argument(help="registered task")],
    suite: Annotated[Optional[str], typer.Option(
        help="a named campaign of the task (e.g. peg-insertion's `stretch`): its methods, variants, conditions, "
             "trials and config; options given here go on top")] = None,
    methods: Annotated[Optional[str], typer.Option(
        help="comma-separated methods [default: the task's own system's method, as for `kintsugi run`]")] = None,
    shapes: Annotated[Optional[str], typer.Option(
        "--shapes", "--variants", help="comma-separated variants [default: the task's first, e.g. round]")] = None,
    conditions: Annotated[Optional[str], typer.Option(
        help="comma-separated conditions [default: the task's, e.g. none,friction,pose,all for the peg]")] = None,
    trials: Annotated[Optional[int], typer.Option(min=1, help="trials per cell [default: 30]")] = None,
    workers: Annotated[int, typer.Option(min=1, help="parallel worker processes")] = 2,
    out: Annotated[Optional[Path], typer.Option(
        help="campaign directory (results.jsonl, report) [default: runs/campaign, or runs/<suite>]")] = None,
    executor: Annotated[str, typer.Option(help="process (default), inline, or ray")] = "process",
    trial_timeout: Annotated[float, typer.Option(
        min=0.001, help="seconds a trial may run before its worker is killed and the trial recorded as failed "
                        "(process executor)")] = 3600.0,
    base_seed: Annotated[int, typer.Option(min=0, help="trial i of every cell uses seed base_seed + i, "
                                                       "so methods meet the same random draws")] = 0,
    videos_per_cell: Annotated[int, typer.Option(min=0, help="record videos of the first N trials per cell")] = 0,
    plugin: PluginOpt = None,
    config_file: ConfigOpt = None,
    set_: SetOpt = None,
    reasoner: ReasonerOpt = "embedded",
    model: ModelOpt = None,
    base_url: BaseUrlOpt = None,
    api_key_env: KeyEnvOpt = "OPENAI_API_KEY",
    structured_output: StructuredOpt = "auto",
) -> None:
    """Run (or resume) a campaign; print its system's tables and write report.md / report.html.

    Every name and setting is checked before the first trial. Exits 1 when any trial errored.
    Plugin modules are imported here and in every worker (the campaign's `plugins`).
    """
    plugin = _plugins(plugin)
    from kintsugi.campaign.plan import campaign_for, suite_of
    from kintsugi.campaign.render import print_tables
    from kintsugi.campaign.report import write_report
    from kintsugi.cli.pages import write_trial_pages
    from kintsugi.campaign.runner import error_summary, run_campaign
    from kintsugi.campaign.tables import tables_for

    try:
        named = suite_of(task, suite, plugin or []) if suite else None
        out = out or Path("runs") / (suite or "campaign")
        cfg = campaign_for(task, _csv(methods) if methods else None, _csv(shapes) if shapes else None,
                           _csv(conditions) if conditions else None, trials, suite, base_seed=base_seed,
                           overrides=_overrides(set_, config_file), plugins=plugin or [],
                           reasoner=_reasoner(reasoner, model, base_url, api_key_env, structured_output),
                           videos_per_cell=videos_per_cell)
        records = run_campaign(cfg, out, workers=workers, executor=executor, trial_timeout_s=trial_timeout)
        print_tables(tables_for(cfg.task, records, cfg), console)
        md, html = write_report(out, cfg, records, trial_pages=write_trial_pages(out, records))
    except KintsugiError as exc:
        _fail(exc)
        return
    console.print(escape(f"results: {out / 'results.jsonl'}   report: {md}, {html}"))
    if named is not None and named.companion:
        console.print(escape(f"beside it (same world, other options): kintsugi bench {task} "
                             f"--suite {named.companion}"))
    errors = error_summary(records)
    if errors:
        _fail(errors, code=1)


@app.command()
def report(out: Annotated[Path, typer.Argument(
        help="campaign directory, or a directory of campaign directories (then also an index.html over them)")],
           index_only: Annotated[bool, typer.Option(
               "--index-only", help="over a directory of campaigns: write only index.html, keeping the reports "
                                    "their `kintsugi bench` wrote")] = False,
           plugin: PluginOpt = None) -> None:
    """Rebuild the tables, report and trial pages of a campaign directory from its results."""
    _plugins(plugin)
    from kintsugi.campaign.store import MANIFEST
    from kintsugi.cli.pages import write_index

    campaigns = [out] if (out / MANIFEST).exists() or not out.is_dir() else sorted(
        p for p in out.iterdir() if (p / MANIFEST).exists())
    if not campaigns:
        _fail(f"{out} holds no campaign ({MANIFEST}) and no campaign directories")
    if index_only and campaigns == [out]:
        _fail(f"--index-only needs a directory of campaign directories; {out} is one campaign")
    missing = [c for c in campaigns if index_only and not (c / "report.html").exists()]
    if missing:
        _fail(f"--index-only: {', '.join(str(c) for c in missing)} has no report.html yet; run `kintsugi report` on it")
    for campaign in campaigns if not index_only else []:
        _report_one(campaign)
    if campaigns != [out]:
        console.print(escape(f"index: {write_index(out, campaigns, title=f'kintsugi: {out.name}')}"))


def _report_one(out: Path) -> None:
    from kintsugi.campaign.plan import expand
    from kintsugi.campaign.render import print_tables
    from kintsugi.campaign.report import write_report
    from kintsugi.campaign.runner import error_summary
    from kintsugi.campaign.store import ResultStore
    from kintsugi.campaign.tables import tables_for
    from kintsugi.cli.pages import write_trial_pages

    try:
        store = ResultStore(out)
        cfg = store.load_config()
        wanted = {s.key for s in expand(cfg)}
        records = [r for r in store.read() if r.key in wanted]  # read once, only this campaign's trials
        md, html = write_report(out, cfg, records, trial_pages=write_trial_pages(out, records))
        print_tables(tables_for(cfg.task, records, cfg), console)
    except KintsugiError as exc:
        _fail(exc)
        return
    console.print(escape(f"report: {md}, {html}"))
    errors = error_summary(records)
    if errors:
        err_console.print(f"[yellow]note:[/yellow] {escape(errors)}")


@app.command()
def explain(
    path: Annotated[Path, typer.Argument(help="a trial record (.json) or a campaign's results.jsonl")],
    key: Annotated[Optional[str], typer.Option(
        help="trial key when PATH holds many records: task/method/variant/condition/seed (or with __)")] = None,
    full: Annotated[bool, typer.Option("--full", "--verbose", help="also print every reasoning call's request "
                                       "and reply, and the figures' long texts (cost code)")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="print the raw record as JSON instead")] = False,
) -> None:
    """Print a trial as one timeline: skills with their outcome, events and reasoning calls in sim-time
    order, then its figures and its outcome."""
    from kintsugi.cli.explain import explain_record, load_record

    try:
        rec = load_record(path, key)
    except KintsugiError as exc:
        _fail(exc)
        return
    if as_json:
        console.print_json(rec.model_dump_json())
    else:
        explain_record(rec, console, full=full)


@app.command()
def graph(
    task: Annotated[str, typer.Argument(help="a tabletop (system B) task, see `kintsugi tasks`")],
    condition: Annotated[str, typer.Option(help="layout condition of the first observation: none, pose, ...")] = "none",
    seed: Annotated[int, typer.Option(min=0, help="seed of the layout draw")] = 0,
    out: Annotated[Optional[Path], typer.Option(help="picture .png (default: runs/graph_<task>.png)")] = None,
    dot: Annotated[Optional[Path], typer.Option(help="also write the graph as a graphviz .dot file")] = None,
    json_out: Annotated[Optional[Path], typer.Option("--json", help="also write the graph as JSON")] = None,
    html_out: Annotated[Optional[Path], typer.Option(
        "--html", help="also write an interactive page (zoom, pan, every box's details on hover)")] = None,
    set_: SetOpt = None,
    reasoner: ReasonerOpt = "embedded",
    model: ModelOpt = None,
    base_url: BaseUrlOpt = None,
    api_key_env: KeyEnvOpt = "OPENAI_API_KEY",
    structured_output: StructuredOpt = "auto",
    plugin: PluginOpt = None,
) -> None:
    """Compile a task's recovery-augmented task graph (composer, arranger, Eq. 8) from its first observation;
    print it and draw it, top to bottom with no overlapping boxes (nominal solid blue, recovery dashed pink)."""
    _plugins(plugin)
    from kintsugi.methods.agentchord.show import compile_for_task, print_graph
    from kintsugi.core.outputs import check_output_file

    try:
        png = check_output_file(out or Path("runs") / f"graph_{task}.png", "picture", (".png",))
        extra = [(p, k, s) for p, k, s in ((dot, "dot file", ".dot"), (json_out, "graph JSON", ".json"),
                                           (html_out, "graph page", ".html")) if p]
        paths = [check_output_file(p, k, (s,)) for p, k, s in extra]
        compiled = compile_for_task(task, condition, seed, _overrides(set_),
                                    _reasoner(reasoner, model, base_url, api_key_env, structured_output))
    except KintsugiError as exc:
        _fail(exc)
        return
    print_graph(compiled, console)
    from kintsugi.taskgraph.render import graph_html, to_dot, write_graph_picture

    writers = {"dot file": to_dot, "graph JSON": lambda g: g.to_json(indent=2), "graph page": graph_html}
    try:
        png.parent.mkdir(parents=True, exist_ok=True)
        write_graph_picture(compiled.graph, png)
        for (_, kind, _), path in zip(extra, paths):
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(writers[kind](compiled.graph))
    except OSError as exc:
        _fail(f"cannot write the graph files: {exc}")
    console.print(escape("picture: " + ", ".join(str(p) for p in [png, *paths])))


@app.command()
def export(
    campaign: Annotated[Path, typer.Argument(help="campaign directory (campaign.json + results.jsonl)")],
    format_: Annotated[Literal["lerobot", "hdf5", "lerobot-v2.1", "trajectory"], typer.Option(
        "--format", help="lerobot (v3.0 layout, any system), hdf5 (robomimic layout), lerobot-v2.1 (tabletop) "
                         "or trajectory (per-trial .npz for the replay policy)")],
    out: Annotated[Path, typer.Option(help="new (or empty) directory to write the dataset into")],
    trials: Annotated[Optional[str], typer.Option(help="which trials, e.g. 'method=agentchord,condition=drop,"
                                                  "seed=0-9,recovered' (fields task method variant condition key "
                                                  "seed; flags recovered nominal success failed ok)")] = None,
    fps: Annotated[float, typer.Option(help="frames per second (must divide the control rate)")] = 10.0,
    plugin: PluginOpt = None,
) -> None:
    """Re-run chosen trials with a recorder and write observations, actions and nominal/recovery segment labels
    for policy learning. A trial whose re-run differs from its record is refused by name (exit 1)."""
    _plugins(plugin)
    from kintsugi.export import export_campaign

    try:
        rep = export_campaign(campaign, format_, out, trials, fps,
                              on_trial=lambda key, what: console.print(escape(f"{key}: {what}")))
    except KintsugiError as exc:
        _fail(exc)
        return
    console.print(escape(f"exported {len(rep.exported)} trials ({sum(e.frames for e in rep.exported)} frames) to "
                         f"{rep.path}"))
    if rep.refused:
        _fail(f"{len(rep.refused)} trials refused: " + "; ".join(f"{k}: {why}" for k, why in rep.refused), code=1)


from kintsugi.cli import info  # noqa: E402,F401 - registers tasks, methods, reasoners and config
from kintsugi.cli import watch_cmd  # noqa: E402,F401 - registers `kintsugi watch` (live page / viewer)


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    app()
