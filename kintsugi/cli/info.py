"""`kintsugi tasks`, `methods`, `reasoners` and `config`: what is registered and every default setting."""

from __future__ import annotations

from typing import Annotated, Optional

import typer
from rich.markup import escape
from rich.table import Table

from kintsugi.cli.app import app
from kintsugi.cli.options import ConfigOpt, PluginOpt, SetOpt, _fail, _overrides, _plugins, console
from kintsugi.core.errors import KintsugiError


def _list(title: str, registry, prefix: str | None = None) -> None:  # noqa: ANN001 - a Registry
    """A registry as a table; with `prefix`, each entry's settings as `--set <prefix>.<key>` defaults."""
    table = Table(title=title)
    table.add_column("name", style="bold")
    table.add_column("description")
    table.add_column("tags", style="dim")
    if prefix:
        table.add_column(f"settings (--set {prefix}.<key>=...)")
    for entry in registry:
        row = [escape(entry.name), escape(entry.description), escape(", ".join(sorted(entry.tags)))]
        if prefix:
            fields = getattr(entry, "config", None)
            defaults = fields().model_dump(mode="json") if fields is not None else {}
            row.append(escape(", ".join(f"{k}={v}" for k, v in defaults.items()) or "—"))
        table.add_row(*row)
    console.print(table)


@app.command()
def tasks(plugin: PluginOpt = None) -> None:
    """List registered tasks with their variants and conditions."""
    _plugins(plugin)
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS

    load_builtins()
    _list("tasks", TASKS)
    for entry in TASKS:
        t = entry.factory()
        console.print(f"[bold]{escape(entry.name)}[/bold] variants: {escape(str(getattr(t, 'variants_help', '')))}")
        conditions = getattr(t, "conditions", {})
        for name in conditions:
            text = conditions[name] if isinstance(conditions, dict) else ""
            console.print(f"  condition [bold]{escape(name)}[/bold]: {escape(text)}")


@app.command()
def methods(plugin: PluginOpt = None) -> None:
    """List registered methods."""
    _plugins(plugin)
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import METHODS

    load_builtins()
    _list("methods", METHODS, prefix="method")


@app.command()
def reasoners(plugin: PluginOpt = None) -> None:
    """List registered reasoner backends."""
    _plugins(plugin)
    from kintsugi.reasoning import REASONERS, load_builtin_backends

    load_builtin_backends()
    _list("reasoners", REASONERS)


@app.command()
def config(
    task: Annotated[str, typer.Argument(help="registered task, see `kintsugi tasks`")],
    method: Annotated[Optional[str], typer.Option(
        help="whose settings to print beside the task's [default: the task's own system's method]")] = None,
    json_: Annotated[bool, typer.Option("--json", help="print JSON instead of YAML")] = False,
    config_file: ConfigOpt = None,
    set_: SetOpt = None,
    plugin: PluginOpt = None,
) -> None:
    """Print every setting of a task and of a method as YAML, with --config and --set applied.

    Save it, edit it and pass it back with `--config file.yaml` to `run` or `bench`: `task:` keys are
    `--set <section>.<key>`, `methods: <name>:` keys are `--set methods.<name>.<key>`."""
    plugin = _plugins(plugin)
    import json

    from kintsugi.campaign.plan import task_defaults
    from kintsugi.core.resolve import settings_document

    try:
        doc = settings_document(task, method or task_defaults(task, plugin)[0], _overrides(set_, config_file))
    except KintsugiError as exc:
        _fail(exc)
        return
    if json_:
        console.print_json(json.dumps(doc))
    else:
        import yaml

        console.print(yaml.safe_dump(doc, sort_keys=False, allow_unicode=True), end="", markup=False,
                      highlight=False)
