"""What every `kintsugi` command shares: the consoles, the option types, and the small parsers and
error exits behind them."""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Annotated, Literal, Optional

import typer
from rich.console import Console
from rich.errors import MarkupError
from rich.markup import escape

from kintsugi.core.errors import KintsugiError

# soft_wrap: piped output (CI, log files) must not be hard-wrapped at 80 columns.
console = Console(soft_wrap=True)
err_console = Console(stderr=True, soft_wrap=True)

SetOpt = Annotated[Optional[list[str]], typer.Option("--set", help="config override key.path=value (repeatable; "
                                                     "goes on top of --config)")]
ConfigOpt = Annotated[Optional[Path], typer.Option(
    "--config", help="YAML (or JSON) settings file in the layout `kintsugi config` prints; --set goes on top")]
ReasonerOpt = Annotated[str, typer.Option(help="reasoner backend: embedded (offline) or openai")]
ModelOpt = Annotated[Optional[str], typer.Option(help="model name for the openai backend")]
BaseUrlOpt = Annotated[Optional[str], typer.Option(help="OpenAI-compatible endpoint (vLLM, Ollama, llama.cpp)")]
KeyEnvOpt = Annotated[str, typer.Option(help="environment variable holding the API key")]
PluginOpt = Annotated[Optional[list[str]], typer.Option(
    "--plugin", metavar="MODULE", help="module to import first, registering its tasks, methods or reasoner backends (repeatable; "
                     "it must be importable, e.g. on PYTHONPATH)")]
StructuredOpt = Annotated[Literal["auto", "strict", "text"], typer.Option(
    help="openai reply format: strict (server-enforced JSON schema / tool calls), text (JSON asked for in the "
         "prompt, parsed tolerantly), auto (strict until the server refuses it, then text)")]



def _version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            number = version("kintsugi")
        except PackageNotFoundError:  # running from a source tree that was never installed
            import kintsugi

            number = kintsugi.__version__
        console.print(f"kintsugi {number}", highlight=False)
        raise typer.Exit()


def _plugins(modules: list[str] | None) -> list[str]:
    """Import `--plugin` modules (after the built-ins) before any name is resolved; one line if one fails."""
    if modules:
        from kintsugi.core.plugins import load_plugins

        try:
            load_plugins(modules)
        except KintsugiError as exc:
            _fail(exc)
    return list(modules or [])


def _csv(text: str) -> list[str]:
    return [x.strip() for x in text.split(",") if x.strip()]


def _reasoner(backend: str, model: str | None, base_url: str | None, key_env: str,  # noqa: ANN202
              structured_output: str = "auto"):
    from kintsugi.core.record import ReasonerSettings

    return ReasonerSettings(backend=backend, model=model, base_url=base_url, api_key_env=key_env,
                            structured_output=structured_output)


def _overrides(sets: list[str] | None, config: Path | None = None) -> dict:
    """`--config` file settings, then `--set key.path=value` on top; campaign validation checks them all
    against the task's and methods' typed configs."""
    from kintsugi.core.config import parse_override
    from kintsugi.core.resolve import load_settings_file

    base = load_settings_file(config) if config is not None else {}
    return base | dict((".".join(k), v) for k, v in (parse_override(s) for s in sets or []))


def _fail(exc: Exception | str, code: int = 2) -> None:
    """One line on stderr naming the problem, then a non-zero exit (2: bad input, 1: a trial failed to run)."""
    err_console.print(f"[bold red]error:[/bold red] {escape(str(exc))}")
    raise typer.Exit(code=code)


def _echo(text: str) -> None:
    """Print one line of a trial's story; a line that is not valid markup is shown verbatim, never fatal."""
    try:
        console.print(text)
    except MarkupError:
        console.print(escape(text))


def _record_path(spec, reasoned: bool = True) -> Path:  # noqa: ANN001 - a TrialSpec
    """runs/<task>__<method>__<variant>__<condition>__<seed>[__<reasoner>][__set-<hash>].json.

    The reasoner (and model) is named when the trial asked it anything (`reasoned`); other `--set` or
    `--config` values add a short hash of the settings, so no record overwrites one made with other settings.
    """
    r = spec.reasoner
    model = r.model
    if model is None and r.backend == "openai":
        from kintsugi.reasoning.openai_backend import DEFAULT_OPENAI_MODEL

        model = DEFAULT_OPENAI_MODEL
    who = ("__" + re.sub(r"[^A-Za-z0-9._+-]+", "-", r.backend + (f"-{model}" if model else ""))) if reasoned else ""
    settings = ""
    if spec.overrides:
        text = json.dumps(spec.overrides, sort_keys=True, default=str)
        settings = "__set-" + hashlib.sha1(text.encode()).hexdigest()[:8]
    return Path("runs") / f"{spec.key.replace('/', '__')}{who}{settings}.json"
