"""`kintsugi watch`: run one trial while a live page (or MuJoCo's viewer) shows it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.markup import escape

from kintsugi.cli.app import app
from kintsugi.cli.options import PluginOpt, SetOpt, _echo, _fail, _overrides, _plugins, console
from kintsugi.core.errors import KintsugiError


@app.command()
def watch(
    task: Annotated[str, typer.Argument(help="registered task, see `kintsugi tasks`")],
    method: Annotated[Optional[str], typer.Option(help="registered method [default: the task's own]")] = None,
    variant: Annotated[Optional[str], typer.Option(help="task variant [default: the task's first]")] = None,
    condition: Annotated[Optional[str], typer.Option(help="condition [default: the task's first default]")] = None,
    seed: Annotated[int, typer.Option(min=0, help="seed of the condition's draws")] = 0,
    live: Annotated[Optional[Path], typer.Option(help="directory for the live page (index.html, frame.jpg)")] = None,
    port: Annotated[Optional[int], typer.Option(help="also serve the live page on http://127.0.0.1:PORT/ "
                                                "(forward it with ssh -L PORT:127.0.0.1:PORT)")] = None,
    viewer: Annotated[bool, typer.Option("--viewer", help="MuJoCo's passive viewer (needs a display)")] = False,
    every: Annotated[float, typer.Option(help="sim seconds between live frames")] = 0.1,
    set_: SetOpt = None,
    plugin: PluginOpt = None,
) -> None:
    """Run one trial and watch it: a live-updating page (over SSH too) or MuJoCo's viewer."""
    plugin = _plugins(plugin)
    from kintsugi.campaign.plan import campaign_for, expand, task_defaults
    from kintsugi.core.runner import run_trial
    from kintsugi.export.live import LivePage, PassiveViewer

    try:
        one = [condition] if condition else [task_defaults(task, plugin)[2][0]]
        cfg = campaign_for(task, [method] if method else None, [variant] if variant else None, one, trials=1,
                           base_seed=seed, overrides=_overrides(set_, None), plugins=plugin)
        spec = expand(cfg)[0]
        if viewer:
            watcher = PassiveViewer()
        else:
            watcher = LivePage(live or Path("runs") / "live", spec.key, every_s=every, port=port)
            console.print(escape(f"live page: {watcher.url}"))
    except KintsugiError as exc:
        _fail(exc)
        return

    def echo(line: str) -> None:
        _echo(line)
        if hasattr(watcher, "echo"):
            watcher.echo(line)

    try:
        result = run_trial(spec, echo=echo, attach=watcher.attach)
    finally:
        watcher.finish()
    console.print(f"ground truth: {'SUCCESS' if result.success else 'FAILURE'}, "
                  f"framework verdict: {'success' if result.framework_success else 'failure'}, sim {result.sim_time:.2f} s")
    if result.error:
        _fail(f"the trial recorded an error: {result.error.splitlines()[0]}", code=1)
