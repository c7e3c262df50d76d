"""The product speaks of the product: README, docs and the package's code hold no development diary.

History (what changed, when, in which work period) belongs in git and CHANGELOG.md. Commit hashes
naming the code a figure was measured on are fine on the benchmark pages; counts of work periods,
issue numbers and before/after anecdotes are not.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PATTERNS = {
    "a work period": re.compile(r"\b(sessions?|work periods?)\b", re.I),
    "an issue number": re.compile(r"\bissues? #?\d+", re.I),
    "before/after a fix": re.compile(r"\b(before|after) the( \w+)? fix\b", re.I),
    "an old value": re.compile(r"\bwas \d", re.I),
    "a count of earlier runs": re.compile(
        r"\b(first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth) (session|run|period)\b|"
        r"\bearlier (run|session|commit)s?\b", re.I),
    "a change log phrase": re.compile(r"\bpreviously\b|\bthe old (plan|bound|value|code)\b", re.I),
}


def product_files() -> list[Path]:
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    return files + sorted((ROOT / "kintsugi").rglob("*.py")) + sorted((ROOT / "kintsugi").rglob("*.md"))


def hits(text: str) -> list[tuple[int, str, str]]:
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        for what, pattern in PATTERNS.items():
            m = pattern.search(line)
            if m:
                out.append((n, what, m.group(0)))
    return out


def test_the_patterns_catch_diary_wording() -> None:
    diary = ["Measured in the seventh session.", "As issue 10 asked.", "Before the contact fix it failed.",
             "It was 1798 steps.", "An earlier run showed it.", "Previously it failed."]
    assert all(hits(line) for line in diary)
    product = ["Each session of the conductor", "the board was moved"]  # not diary: no hit on plain words
    assert not hits(product[1])


def test_no_diary_in_readme_docs_or_code() -> None:
    files = product_files()
    assert len(files) > 100 and (ROOT / "README.md") in files
    found = [f"{p.relative_to(ROOT)}:{n}: {what} ({text!r})" for p in files for n, what, text in hits(p.read_text())]
    assert not found, "development-diary wording (say what the code does; history goes to git):\n" + "\n".join(found)
