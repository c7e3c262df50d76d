"""Draw a TextTable three ways: rich (console), Markdown (report.md), HTML (report.html)."""

from __future__ import annotations

import html
from typing import Iterable

from rich import box
from rich.console import Console
from rich.markup import escape
from rich.measure import Measurement
from rich.table import Table

from kintsugi.campaign.tables import TextTable

_LEFT = {"Task", "Method", "Variant", "Condition", "From \\ To"}


def to_rich(t: TextTable) -> Table:
    """Every string is escaped: names and values come from records and users, not from us."""
    table = Table(
        title=escape(t.title), caption=escape(" ".join(t.notes)) or None, caption_justify="left",
        box=box.SIMPLE_HEAD, pad_edge=False,
    )
    for i, col in enumerate(t.columns):
        # Cells never wrap (an interval split over two lines is unreadable); headers may.
        widest = max((len(row[i]) for row in t.rows), default=1)
        table.add_column(escape(col), justify="left" if col in _LEFT else "right", min_width=widest)
    for row in t.rows:
        table.add_row(*(escape(v) for v in row))
    return table


def print_tables(tables: Iterable[TextTable], console: Console | None = None) -> None:
    console = console or Console()
    for t in tables:
        table = to_rich(t)
        # Piped output (CI logs, files) defaults to 80 columns; widen rather than crop.
        saved = console.width
        if not console.is_terminal:
            console.width = max(saved, Measurement.get(console, console.options.update_width(1000), table).maximum)
        try:
            console.print(table)
            console.print()
        finally:
            console.width = saved


def _md_escape(text: str) -> str:
    return text.replace("|", "\\|")


def to_markdown(t: TextTable) -> str:
    align = [":--" if c in _LEFT else "--:" for c in t.columns]
    lines = [f"### {t.title}", ""]
    lines.append("| " + " | ".join(_md_escape(c) for c in t.columns) + " |")
    lines.append("| " + " | ".join(align) + " |")
    lines += ["| " + " | ".join(_md_escape(c) for c in row) + " |" for row in t.rows]
    if t.notes:
        lines += [""] + [f"_{n}_" for n in t.notes]
    return "\n".join(lines) + "\n"


def to_html(t: TextTable) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(c)}</th>" for c in t.columns)
    body = "".join(
        "<tr>" + "".join(
            f'<td class="{"l" if c in _LEFT else "r"}">{esc(v)}</td>' for c, v in zip(t.columns, row)
        ) + "</tr>"
        for row in t.rows
    )
    notes = "".join(f'<p class="note">{esc(n)}</p>' for n in t.notes)
    return f"<h3>{esc(t.title)}</h3><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>{notes}"
