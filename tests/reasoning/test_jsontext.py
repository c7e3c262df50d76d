"""The tolerant JSON extractor: fixed cases, and hypothesis properties (only BadReply escapes; objects survive)."""

from __future__ import annotations

import json
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from kintsugi.core.errors import ReasoningError
from kintsugi.reasoning.jsontext import BadReply, extract_json_object, repair

FUZZ = settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])

OBJ = {"success": True, "explanation": "peg {inside} the hole, isn't it \"fine\"", "n": [1, 2.5, None]}


@pytest.mark.parametrize("text", [
    json.dumps(OBJ),
    "```json\n" + json.dumps(OBJ, indent=2) + "\n```",
    "Sure! Here is my answer:\n```\n" + json.dumps(OBJ) + "\n```\nLet me know {if} you need more.",
    "I looked at {the image}. " + json.dumps(OBJ) + " That is all.",
    json.dumps(OBJ)[:-1] + ",}",
    "{'success': True, 'explanation': 'peg {inside} the hole, isn\\'t it \"fine\"', 'n': [1, 2.5, None,],}",
    '{success: true, explanation: "peg {inside} the hole, isn\'t it \\"fine\\"", n: [1, 2.5, null]}',
])
def test_extracts_the_object_from_common_breakage(text: str) -> None:
    assert extract_json_object(text) == OBJ


@pytest.mark.parametrize("text, problem", [
    (None, "empty"), ("   ", "empty"), ("I think the peg is in.", "no JSON object"), ("[1, 2]", "no JSON object"),
    ('{"success": tru', "not valid JSON"), ('{"a": ' + "9" * 5000 + "}", "not valid JSON"),
    ("{" * 50_000 + "}" * 50_000, "not valid JSON"), ('{"a": ' + "[" * 50_000 + "]" * 50_000 + "}", "not valid JSON"),
])
def test_garbage_is_a_bad_reply_that_says_what_to_do(text: str | None, problem: str) -> None:
    with pytest.raises(BadReply, match=problem) as info:
        extract_json_object(text)
    assert "JSON object" in str(info.value)


def test_repair_never_touches_double_quoted_strings() -> None:
    text = '{"a": "x, } True \'q\' key: 1",}'
    assert repair(text) == '{"a": "x, } True \'q\' key: 1"}'


def test_first_balanced_object_wins() -> None:
    assert extract_json_object('{"a": 1} and then {"b": 2}') == {"a": 1}
    assert extract_json_object('{"a": {"b": {"c": [1, {"d": 2}]}}}') == {"a": {"b": {"c": [1, {"d": 2}]}}}


# --- properties ------------------------------------------------------------

def _check(text: str) -> None:
    try:
        value = extract_json_object(text)
    except ReasoningError as exc:
        assert isinstance(exc, BadReply) and str(exc)
    else:
        assert isinstance(value, dict)


@FUZZ
@given(st.text())
def test_any_text_gives_a_dict_or_bad_reply(text: str) -> None:
    _check(text)


@FUZZ
@given(st.lists(st.sampled_from(list("{}[]\"',:`\\ \n") + ["True", "None", "1", "a", "```json\n", "1e999", "NaN"]),
                max_size=60).map("".join))
def test_json_like_noise_gives_a_dict_or_bad_reply(text: str) -> None:
    _check(text)


_SCALARS = st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=False, allow_infinity=False) \
    | st.text(max_size=12)
_JSON = st.recursive(_SCALARS, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                                            max_size=4), max_leaves=12)
_OBJECTS = st.dictionaries(st.text(max_size=8), _JSON, max_size=5)
_PROSE = st.text(alphabet=st.characters(blacklist_characters="{}`", blacklist_categories=("Cs",)), max_size=40)


def _with_trailing_commas(value: Any) -> str:
    """JSON with a trailing comma in every non-empty container, as small models write it."""
    if isinstance(value, dict) and value:
        return "{" + ", ".join(f"{json.dumps(k)}: {_with_trailing_commas(v)}" for k, v in value.items()) + ",}"
    if isinstance(value, list) and value:
        return "[" + ", ".join(_with_trailing_commas(v) for v in value) + ",]"
    return json.dumps(value)


@FUZZ
@given(_OBJECTS, _PROSE, _PROSE, st.booleans(), st.booleans())
def test_objects_survive_prose_fences_and_trailing_commas(obj: dict, before: str, after: str, fenced: bool,
                                                         commas: bool) -> None:
    body = _with_trailing_commas(obj) if commas else json.dumps(obj, indent=1)
    text = f"{before}\n```json\n{body}\n```\n{after}" if fenced else f"{before} {body} {after}"
    assert extract_json_object(text) == obj


@FUZZ
@given(st.dictionaries(st.text(alphabet="abc xyz'\"", max_size=6),
                       st.none() | st.booleans() | st.integers() | st.text(alphabet="abc xyz'\",:{}[]", max_size=8),
                       max_size=5))
def test_python_style_dicts_are_repaired(obj: dict) -> None:
    assert extract_json_object(f"Answer: {obj!r}") == obj
