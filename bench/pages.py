"""The benchmark pages' writer: a bench script puts its tables into a page under docs/, with the command
that made them, the date, the commit and the machine.

A page keeps its hand-written text; each script owns one block of it, between
`<!-- begin: <name> -->` and `<!-- end: <name> -->` markers, and rewrites only that block (a page or
a block that does not exist yet is created, the block appended at the end).

    from bench.pages import Block, write_block
    write_block("docs/benchmarks-peg.md", Block("bench_peg", command, ["| figure | value |", ...]))
"""

from __future__ import annotations

import re
import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Block:
    """What a bench script writes: its name (the block's marker), the command line, and Markdown lines."""

    name: str
    command: str
    lines: list[str] = field(default_factory=list)

    def render(self) -> str:
        from kintsugi.campaign.report import machine_info

        info = machine_info()
        head = (f"Written by `{self.command}` on {info['date']}, commit {info['commit']}; machine: "
                f"{info['platform']}, {info['cpu_count']} CPUs, Python {info['python']}, mujoco {info['mujoco']}.")
        return "\n".join([f"<!-- begin: {self.name} -->", head, "", *self.lines, f"<!-- end: {self.name} -->"])


def command_line() -> str:
    """This process's command line as a user would type it (`.venv/bin/python bench/x.py --flag`)."""
    script = Path(sys.argv[0])
    try:
        script = script.resolve().relative_to(Path.cwd())
    except ValueError:
        pass
    return " ".join([".venv/bin/python", shlex.quote(str(script)), *(shlex.quote(a) for a in sys.argv[1:])])


def write_block(page: str | Path, block: Block, title: str | None = None) -> Path:
    """Put `block` into `page` (replacing the block of the same name, else appending it); returns the page."""
    path = Path(page)
    text = path.read_text() if path.exists() else f"# {title or path.stem}\n"
    pattern = re.compile(rf"<!-- begin: {re.escape(block.name)} -->.*?<!-- end: {re.escape(block.name)} -->",
                         flags=re.S)
    rendered = block.render()
    if pattern.search(text):
        text = pattern.sub(lambda _: rendered, text, count=1)
    else:
        text = text.rstrip("\n") + "\n\n" + rendered + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def campaign_tables(out_dir: str | Path) -> list[str]:
    """A campaign directory's system tables as Markdown lines (the tables `kintsugi report` writes)."""
    from kintsugi.campaign.plan import expand
    from kintsugi.campaign.render import to_markdown
    from kintsugi.campaign.store import ResultStore
    from kintsugi.campaign.tables import tables_for

    store = ResultStore(out_dir)
    cfg = store.load_config()
    wanted = {s.key for s in expand(cfg)}
    records = [r for r in store.read() if r.key in wanted]
    lines = [f"Campaign `{out_dir}`: task `{cfg.task}`, methods {', '.join(cfg.methods)}, "
             f"{cfg.trials} trials per cell from seed {cfg.base_seed}, {len(records)} recorded.", ""]
    for table in tables_for(cfg.task, records, cfg):
        lines += [*to_markdown(table).splitlines(), ""]
    return lines


def main(argv: list[str]) -> int:
    """`bench/pages.py PAGE NAME CAMPAIGN_DIR...`: write the campaigns' tables into PAGE's block NAME."""
    if len(argv) < 3:
        print(__doc__.split("\n\n")[0] + "\nusage: bench/pages.py PAGE NAME CAMPAIGN_DIR...", file=sys.stderr)
        return 2
    page, name, *dirs = argv
    lines = [line for d in dirs for line in campaign_tables(d)]
    print(write_block(page, Block(name, command_line(), lines)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))


def table_lines(tables: list) -> list[str]:
    """Campaign tables (`TextTable`s) as Markdown lines."""
    from kintsugi.campaign.render import to_markdown

    return [line for t in tables for line in (*to_markdown(t).splitlines(), "")]


def pop_page(argv: list[str]) -> tuple[str | None, list[str]]:
    """(`--page PATH` if given, the other arguments): for scripts that read their own argv."""
    if "--page" not in argv:
        return None, argv
    i = argv.index("--page")
    if i + 1 >= len(argv):
        raise SystemExit("--page needs a path, e.g. --page docs/benchmarks-agentchord.md")
    return argv[i + 1], argv[:i] + argv[i + 2:]
