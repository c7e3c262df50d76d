"""The `kintsugi` command: the Typer app every command module registers on."""

from __future__ import annotations

from typing import Annotated

import typer

from kintsugi.cli.options import _version

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="kintsugi: resilient robot manipulation with reasoned checks and recovery, on MuJoCo.")


@app.callback()
def _main(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="print the installed version and exit")] = False,
) -> None:
    """kintsugi: resilient robot manipulation with reasoned checks and recovery, on MuJoCo."""
