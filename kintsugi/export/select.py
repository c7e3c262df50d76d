"""Which trials of a campaign to export: a small filter language over the trial key and the record.

`--trials "method=agentchord,condition=drop|shift,seed=0-9,recovered"` keeps trials whose every term holds.
Terms, separated by commas:
- `task=`, `method=`, `variant=`, `condition=`, `key=`: shell-style patterns (`*`, `?`), `|` between alternatives;
- `seed=`: integers or inclusive ranges `a-b`, `|` between alternatives;
- flags `recovered` (the method ran a recovery: a recorded transition or a recovery action), `nominal` (none),
  `success`, `failed` (scored outcome), `ok` (no recorded error).
A term the language does not know is an error naming it, never a filter that silently keeps everything.
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field

from kintsugi.core.errors import ConfigError
from kintsugi.core.record import TrialRecord

FIELDS = ("task", "method", "variant", "condition", "key", "seed")
FLAGS = ("recovered", "nominal", "success", "failed", "ok")


def had_recovery(record: TrialRecord) -> bool:
    """What the method reported: a failure -> recovery transition, or an action it marked as recovery."""
    return bool(record.transitions) or any(s.recovery for s in record.skills)


@dataclass(frozen=True)
class TrialFilter:
    text: str = ""
    patterns: dict[str, tuple[str, ...]] = field(default_factory=dict)
    seeds: tuple[tuple[int, int], ...] = ()
    flags: frozenset[str] = frozenset()

    def keeps(self, record: TrialRecord) -> bool:
        for name, alts in self.patterns.items():
            value = str(getattr(record, name))
            if not any(fnmatch.fnmatchcase(value, a) for a in alts):
                return False
        if self.seeds and not any(lo <= record.seed <= hi for lo, hi in self.seeds):
            return False
        rec = had_recovery(record)
        checks = {"recovered": rec, "nominal": not rec, "success": record.success, "failed": not record.success,
                  "ok": record.error is None}
        return all(checks[f] for f in self.flags)


def parse_filter(text: str | None) -> TrialFilter:
    """Parse the `--trials` text; an empty or missing filter keeps every trial."""
    text = (text or "").strip()
    patterns: dict[str, tuple[str, ...]] = {}
    seeds: list[tuple[int, int]] = []
    flags: set[str] = set()
    for raw in text.split(",") if text else []:
        term = raw.strip()
        if not term:
            raise ConfigError(f"--trials {text!r}: an empty term (two commas in a row?)")
        if "=" not in term:
            if term not in FLAGS:
                raise ConfigError(f"--trials: unknown flag {term!r}; flags: {', '.join(FLAGS)}; "
                                  f"fields: {', '.join(f + '=' for f in FIELDS)}")
            flags.add(term)
            continue
        name, _, value = (p.strip() for p in term.partition("="))
        if name not in FIELDS:
            raise ConfigError(f"--trials: unknown field {name!r} in {term!r}; fields: {', '.join(FIELDS)}")
        alts = tuple(a.strip() for a in value.split("|"))
        if not value or any(not a for a in alts):
            raise ConfigError(f"--trials: {term!r} has an empty value")
        if name in patterns or (name == "seed" and seeds):
            raise ConfigError(f"--trials: field {name!r} given twice; use '|' between alternatives")
        if name == "seed":
            seeds.extend(_seed_range(a, term) for a in alts)
        else:
            patterns[name] = alts
    if {"recovered", "nominal"} <= flags or {"success", "failed"} <= flags:
        raise ConfigError(f"--trials {text!r} asks for contradictory flags; no trial could match")
    return TrialFilter(text, patterns, tuple(seeds), frozenset(flags))


def _seed_range(text: str, term: str) -> tuple[int, int]:
    lo, sep, hi = text.partition("-")
    try:
        a = int(lo)
        b = int(hi) if sep else a
    except ValueError:
        raise ConfigError(f"--trials: {term!r}: seeds are integers or ranges a-b, not {text!r}") from None
    if b < a:
        raise ConfigError(f"--trials: {term!r}: range {text!r} is empty (end before start)")
    return a, b
