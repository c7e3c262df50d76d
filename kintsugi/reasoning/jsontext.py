"""One JSON object out of a model's free text, and pydantic errors as text a model can act on.

Servers without strict structured output leave the format to the model, and
small models wrap JSON in code fences, add prose, leave trailing commas or
write Python-style dicts. `extract_json_object` takes the first balanced object
that parses, after repairs that only touch the text *outside* JSON strings (so
a value is never changed), and fails only with `BadReply`, whose message can be
quoted back to the model.
"""

from __future__ import annotations

import json
import re
from typing import Any

from pydantic import ValidationError

from kintsugi.core.errors import ReasoningError

MAX_CANDIDATES = 16
"""Brace groups tried before giving up; prose rarely holds more before the answer."""

_FENCE = re.compile(r"```[ \t]*[A-Za-z0-9_+-]*[ \t]*\r?\n?(.*?)```", re.S)
# One token of the scan: a double- or single-quoted string (maybe unterminated), or a brace.
_DOUBLE = r'"(?:[^"\\]|\\.)*"?'
_SINGLE = r"'(?:[^'\\]|\\.)*'?"
_SCAN = {False: re.compile(rf"{_DOUBLE}|[{{}}]", re.S), True: re.compile(rf"{_DOUBLE}|{_SINGLE}|[{{}}]", re.S)}
_REPAIR_TOKEN = re.compile(rf"({_DOUBLE})|({_SINGLE})|([^\"']+)", re.S)
_TRAILING_COMMA = re.compile(r",(\s*[}\]])")
_BARE_KEY = re.compile(r"([{,]\s*)([A-Za-z_][A-Za-z0-9_]*)(\s*:)")
_PY_LITERALS = re.compile(r"\b(True|False|None)\b")
_JSON_LITERAL = {"True": "true", "False": "false", "None": "null"}


class BadReply(ReasoningError):
    """One reply could not be used; its message is quoted back to the model for repair."""


def extract_json_object(text: str | None) -> dict[str, Any]:
    """The first JSON object in `text`: fenced blocks first, then the whole text.

    Raises `BadReply` (and nothing else) when there is none.
    """
    if text is None or not text.strip():
        raise BadReply("the reply was empty; answer with one JSON object")
    direct = loads_object(text)
    if direct is not None:
        return direct
    for chunk in [m.group(1) for m in _FENCE.finditer(text)] + [text]:
        found = _first_object(chunk)
        if found is not None:
            return found
    if "{" not in text:
        raise BadReply("the reply holds no JSON object; answer with one JSON object and nothing else")
    raise BadReply(
        "the reply is not valid JSON (no balanced {...} object parses, even after removing trailing commas "
        "and fixing quotes); answer with one JSON object and nothing else"
    )


def loads_object(text: str) -> dict[str, Any] | None:
    """`json.loads(text)` if that is an object, else None (never raises)."""
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):  # ValueError covers JSONDecodeError and over-long integers
        return None
    return value if isinstance(value, dict) else None


def _first_object(chunk: str) -> dict[str, Any] | None:
    pos = 0
    for _ in range(MAX_CANDIDATES):
        start = chunk.find("{", pos)
        if start < 0:
            return None
        ends = []
        for single_quotes in (False, True):
            end = _balanced_end(chunk, start, single_quotes)
            if end is None or end in ends:
                continue
            ends.append(end)
            span = chunk[start:end]
            found = loads_object(span)
            if found is None:
                found = loads_object(repair(span))
            if found is not None:
                return found
        if not ends:
            return None  # unbalanced from here on: everything after is inside this brace
        pos = min(ends)
    return None


def _balanced_end(text: str, start: int, single_quotes: bool) -> int | None:
    """Index just past the `}` closing the `{` at `start`, skipping braces inside strings."""
    depth = 0
    for m in _SCAN[single_quotes].finditer(text, start):
        token = m.group()
        if token == "{":
            depth += 1
        elif token == "}":
            depth -= 1
            if depth == 0:
                return m.end()
    return None


def repair(span: str) -> str:
    """Common breakage fixed outside strings: single quotes, trailing commas, bare keys, Python literals."""
    out = []
    for double, single, other in _REPAIR_TOKEN.findall(span):
        if double:
            out.append(double)
        elif single:
            out.append(_single_to_double(single))
        else:
            other = _TRAILING_COMMA.sub(r"\1", other)
            other = _PY_LITERALS.sub(lambda m: _JSON_LITERAL[m.group()], other)
            out.append(_BARE_KEY.sub(r'\1"\2"\3', other))
    return "".join(out)


def _single_to_double(token: str) -> str:
    body = token[1:-1] if len(token) > 1 and token.endswith("'") else token[1:]
    body = re.sub(r"\\(.)|\"", lambda m: ("'" if m.group(1) == "'" else m.group()) if m.group(1) else '\\"', body,
                  flags=re.S)
    return f'"{body}"'


def describe_validation_error(exc: ValidationError, limit: int = 8) -> str:
    """Compact 'where: what' lines from a pydantic error, without echoing huge inputs."""
    lines = []
    for err in exc.errors(include_url=False, include_input=False)[:limit]:
        where = ".".join(str(p) for p in err["loc"]) or "(top level)"
        lines.append(f"{where}: {err['msg']}")
    more = exc.error_count() - limit
    if more > 0:
        lines.append(f"... and {more} more problems")
    return "; ".join(lines)
