"""Command line: run one trial, run a campaign, list what is registered, explain a trial."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console
from rich.table import Table

from kintsugi.errors import KintsugiError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="kintsugi: resilient robot manipulation with reasoned checks and recovery, on MuJoCo.")
console = Console()

SetOpt = Annotated[Optional[list[str]], typer.Option("--set", help="config override key.path=value (repeatable)")]
ReasonerOpt = Annotated[str, typer.Option(help="reasoner backend: embedded (offline) or openai")]
ModelOpt = Annotated[Optional[str], typer.Option(help="model name for the openai backend")]
BaseUrlOpt = Annotated[Optional[str], typer.Option(help="OpenAI-compatible endpoint (vLLM, Ollama, llama.cpp)")]
KeyEnvOpt = Annotated[str, typer.Option(help="environment variable holding the API key")]


def _csv(text: str) -> list[str]:
    return [x.strip() for x in text.split(",") if x.strip()]


def _reasoner(backend: str, model: str | None, base_url: str | None, key_env: str):  # noqa: ANN202
    from kintsugi.trial import ReasonerSettings

    return ReasonerSettings(backend=backend, model=model, base_url=base_url, api_key_env=key_env)


def _overrides(task_name: str, sets: list[str] | None) -> dict:
    """Validate `--set` against the task's typed config now, so a typo fails before any trial runs."""
    from kintsugi.config import parse_override
    from kintsugi.tasks import TASKS, load_all

    load_all()
    task = TASKS.get(task_name).factory()
    pairs = dict((".".join(k), v) for k, v in (parse_override(s) for s in sets or []))
    task.config(pairs)
    return pairs


def _fail(exc: Exception) -> None:
    console.print(f"[bold red]error:[/bold red] {exc}")
    raise typer.Exit(code=2)


@app.command()
def run(
    task: Annotated[str, typer.Argument(help="registered task, see `kintsugi tasks`")],
    method: Annotated[str, typer.Option(help="registered method, see `kintsugi methods`")] = "baseline",
    shape: Annotated[str, typer.Option("--shape", "--variant", help="task variant (peg shape)")] = "round",
    condition: Annotated[str, typer.Option(help="randomized condition: none, friction, pose, all")] = "none",
    seed: int = 0,
    video: Annotated[Optional[Path], typer.Option(help="write an .mp4 or .gif of the scene camera")] = None,
    record: Annotated[Optional[Path], typer.Option(help="trial record JSON (default runs/<key>.json)")] = None,
    set_: SetOpt = None,
    reasoner: ReasonerOpt = "embedded",
    model: ModelOpt = None,
    base_url: BaseUrlOpt = None,
    api_key_env: KeyEnvOpt = "OPENAI_API_KEY",
) -> None:
    """Run one trial, tell its story skill by skill, and save its record (and video)."""
    from kintsugi.tasks import TASKS
    from kintsugi.trial import TrialSpec

    try:
        spec = TrialSpec(task=task, method=method, variant=shape, condition=condition, seed=seed,
                         overrides=_overrides(task, set_), reasoner=_reasoner(reasoner, model, base_url, api_key_env),
                         video=str(video) if video else None)
        console.rule(f"[bold]{spec.key}[/bold]")
        result = TASKS.get(task).factory().run(spec, echo=console.print)
    except KintsugiError as exc:
        _fail(exc)
        return
    path = record or Path("runs") / (spec.key.replace("/", "__") + ".json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(result.model_dump_json(indent=2))
    colour = "green" if result.success else "red"
    console.print(f"[bold {colour}]ground truth: {'SUCCESS' if result.success else 'FAILURE'}[/bold {colour}]"
                  f"  framework verdict: {'success' if result.framework_success else 'failure'}"
                  f"  sim {result.sim_time:.2f} s, wall {result.wall_time:.2f} s, "
                  f"{result.reasoning_calls} reasoning calls")
    if result.error:
        console.print(f"[red]error:[/red] {result.error}")
    console.print(f"record: {path}" + (f"   video: {result.video}" if result.video else ""))


@app.command()
def bench(
    task: Annotated[str, typer.Argument(help="registered task")],
    methods: Annotated[str, typer.Option(help="comma-separated methods")] = "baseline",
    shapes: Annotated[str, typer.Option("--shapes", "--variants", help="comma-separated variants")] = "round",
    conditions: Annotated[str, typer.Option(help="comma-separated conditions")] = "none,friction,pose,all",
    trials: Annotated[int, typer.Option(help="trials per cell")] = 30,
    workers: Annotated[int, typer.Option(help="parallel worker processes")] = 2,
    out: Annotated[Path, typer.Option(help="campaign directory (results.jsonl, report)")] = Path("runs/campaign"),
    executor: Annotated[str, typer.Option(help="process (default), inline, or ray")] = "process",
    base_seed: int = 0,
    videos_per_cell: Annotated[int, typer.Option(help="record videos of the first N trials per cell")] = 0,
    plugin: Annotated[Optional[list[str]], typer.Option(help="module to import in workers (extra tasks)")] = None,
    set_: SetOpt = None,
    reasoner: ReasonerOpt = "embedded",
    model: ModelOpt = None,
    base_url: BaseUrlOpt = None,
    api_key_env: KeyEnvOpt = "OPENAI_API_KEY",
) -> None:
    """Run (or resume) a campaign; print the paper's tables and write report.md / report.html."""
    from kintsugi.campaign.plan import CampaignConfig
    from kintsugi.campaign.render import print_tables
    from kintsugi.campaign.report import write_report
    from kintsugi.campaign.runner import run_campaign
    from kintsugi.campaign.tables import all_tables

    try:
        cfg = CampaignConfig(
            task=task, methods=_csv(methods), variants=_csv(shapes), conditions=_csv(conditions), trials=trials,
            base_seed=base_seed, overrides=_overrides(task, set_), plugins=plugin or [],
            reasoner=_reasoner(reasoner, model, base_url, api_key_env), videos_per_cell=videos_per_cell)
        records = run_campaign(cfg, out, workers=workers, executor=executor)
        print_tables(all_tables(records, cfg), console)
        md, html = write_report(out, cfg, records)
    except KintsugiError as exc:
        _fail(exc)
        return
    console.print(f"results: {out / 'results.jsonl'}   report: {md}, {html}")


@app.command()
def report(out: Annotated[Path, typer.Argument(help="campaign directory")]) -> None:
    """Rebuild the tables and report of a campaign directory from its results."""
    from kintsugi.campaign.plan import expand
    from kintsugi.campaign.render import print_tables
    from kintsugi.campaign.report import write_report
    from kintsugi.campaign.store import ResultStore
    from kintsugi.campaign.tables import all_tables

    try:
        store = ResultStore(out)
        cfg = store.load_config()
        wanted = {s.key for s in expand(cfg)}
        records = [r for r in store.read() if r.key in wanted]  # read once, only this campaign's trials
        md, html = write_report(out, cfg, records)
        print_tables(all_tables(records, cfg), console)
    except KintsugiError as exc:
        _fail(exc)
        return
    console.print(f"report: {md}, {html}")


def _list(title: str, registry) -> None:  # noqa: ANN001 - a Registry
    table = Table(title=title)
    table.add_column("name", style="bold")
    table.add_column("description")
    table.add_column("tags", style="dim")
    for entry in registry:
        table.add_row(entry.name, entry.description, ", ".join(sorted(entry.tags)))
    console.print(table)


@app.command()
def tasks() -> None:
    """List registered tasks with their variants and conditions."""
    from kintsugi.tasks import TASKS, load_all

    load_all()
    _list("tasks", TASKS)
    for entry in TASKS:
        t = entry.factory()
        console.print(f"[bold]{entry.name}[/bold] variants: {t.variants_help}")
        for name, text in t.conditions.items():
            console.print(f"  condition [bold]{name}[/bold]: {text}")


@app.command()
def methods() -> None:
    """List registered methods."""
    import kintsugi.methods.builtin  # noqa: F401
    from kintsugi.methods import METHODS

    _list("methods", METHODS)


@app.command()
def reasoners() -> None:
    """List registered reasoner backends."""
    from kintsugi.reasoning import REASONERS, load_builtin_backends

    load_builtin_backends()
    _list("reasoners", REASONERS)


@app.command()
def explain(
    path: Annotated[Path, typer.Argument(help="a trial record (.json) or a campaign's results.jsonl")],
    key: Annotated[Optional[str], typer.Option(help="trial key, when PATH holds many records")] = None,
) -> None:
    """Print a trial's story: each skill, its verdict, and the full reasoning transcript."""
    from kintsugi.explain import explain_record, load_record

    try:
        rec = load_record(path, key)
    except KintsugiError as exc:
        _fail(exc)
        return
    explain_record(rec, console)


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    app()
