"""The controlled language's instruction suite (instructions.yaml): every instruction reads as exactly its
expected goal (arms, bindings, held-up objects where the case gives them) or is refused with the expected
reason; a reading that differs is a silent misreading, and there are none. `python -m
tests.methods.agentchord.test_instruction_suite` prints how many are understood and refused."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.language import NotUnderstood, Scene
from kintsugi.methods.agentchord.reading import read

SUITE = yaml.safe_load((Path(__file__).parent / "instructions.yaml").read_text())
WORDS = frozenset({p.name for p in TABLETOP_DOMAIN.predicates} | set(TABLETOP_DOMAIN.aliases))
CASES = SUITE["cases"]


def scene(name: str) -> Scene:
    s = SUITE["scenes"][name]
    objs = s["objects"]
    return Scene.of(list(objs), arms=s.get("arms", ("left", "right")), regions=s.get("regions", ()),
                    directions=tuple(TABLETOP_DOMAIN.directions),
                    kinds={n: o.get("kind", "") for n, o in objs.items()},
                    colours={n: o.get("colour") for n, o in objs.items()},
                    stands={n: o.get("stands") for n, o in objs.items()})


def outcome(case: dict) -> tuple[str, str]:
    """("understood", "") when the reading is exactly the expected one, ("refused", "") when refused as
    expected, else ("misread" | "wrong refusal" | "refused", what happened)."""
    try:
        r = read(case["text"], scene(case["scene"]), WORDS)
    except NotUnderstood as exc:
        if "refuse" in case and re.search(case["refuse"], str(exc)):
            return "refused", ""
        return ("wrong refusal" if "refuse" in case else "refused"), str(exc)
    if "goal" not in case:
        return "misread", f"read as {r.goal} where a refusal matching {case['refuse']!r} was expected"
    got = {"goal": sorted(r.goal), "arms": r.arms, "bindings": r.bindings, "held_up": r.held_up}
    want = {"goal": sorted(case["goal"]), **{k: case[k] for k in ("arms", "bindings", "held_up") if k in case}}
    wrong = {k: (got[k], v) for k, v in want.items() if (sorted(got[k]) if k == "arms" else got[k]) != (
        sorted(v) if k == "arms" else v)}
    return ("misread", f"{wrong}") if wrong else ("understood", "")


def test_the_suite_is_large_and_well_formed() -> None:
    assert len(CASES) >= 100
    assert all(("goal" in c) != ("refuse" in c) for c in CASES), [c["text"] for c in CASES if ("goal" in c) == ("refuse" in c)]
    assert sum("refuse" in c for c in CASES) >= 30 and sum("goal" in c for c in CASES) >= 50
    assert len({(c["scene"], c["text"]) for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[f"{i:03d}" for i in range(len(CASES))])
def test_each_instruction_reads_as_expected(case: dict) -> None:
    kind, why = outcome(case)
    assert kind in ("understood", "refused"), f"{case['text']!r}: {kind}: {why}"


def test_every_goal_uses_only_the_domains_words() -> None:
    from kintsugi.methods.agentchord.types import parse_atom

    for c in CASES:
        for g in c.get("goal", []):
            assert parse_atom(g)[1] in WORDS, g


def summary() -> dict[str, int]:
    out: dict[str, int] = {}
    for c in CASES:
        kind = outcome(c)[0]
        out[kind] = out.get(kind, 0) + 1
    return out


def test_summary_counts_no_silent_misreading(capsys: pytest.CaptureFixture) -> None:
    s = summary()
    with capsys.disabled():
        print(f"\ninstruction suite: {len(CASES)} instructions: {s.get('understood', 0)} understood, "
              f"{s.get('refused', 0)} refused as expected, {s.get('misread', 0)} silent misreadings")
    assert s.get("misread", 0) == 0


if __name__ == "__main__":
    s = summary()
    print(f"{len(CASES)} instructions: {s}")
