"""Physics priors: the embedded material table (golden values, never the truth) and the checks every
backend's reply goes through, fuzzed with hostile replies: each is a clear BadReply or bounded values."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.coral.types import ObjectView, PriorsRequest
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.methods.coral.priors import (
    DENSITY_BOUNDS_KG_M3,
    FRICTION_BOUNDS,
    MASS_BOUNDS_KG,
    check_priors,
    embedded_priors,
    material_of,
    parse_priors,
)

BOARD = ObjectView(label="cutting board", size_m=(0.35, 0.25, 0.02))
BOX = ObjectView(label="cardboard box", size_m=(0.2, 0.15, 0.1))
REQUEST = PriorsRequest(task="push the board until its handle overhangs, then pick it", objects=[BOARD, BOX])


@pytest.mark.parametrize(("label", "material"), [
    ("cutting board", "wood"), ("Wooden Block", "wood"), ("small cardboard box", "cardboard"), ("box", "cardboard"),
    ("steel can", "metal"), ("coffee mug", "ceramic"), ("foam cube", "foam"), ("mystery object", "unknown"),
    ("boxer", "unknown"),  # whole words only
])
def test_material_from_the_label(label: str, material: str) -> None:
    assert material_of(label).name == material


def test_embedded_priors_are_density_times_model_volume() -> None:
    reply = embedded_priors(REQUEST)
    assert reply.objects["cutting board"].mass_kg == pytest.approx(650 * 0.35 * 0.25 * 0.02)
    assert reply.objects["cardboard box"].mass_kg == pytest.approx(180 * 0.2 * 0.15 * 0.1)
    assert reply.objects["cutting board"].friction == 0.45
    checked, notes = check_priors(reply, REQUEST)
    assert checked == reply and notes == []


def test_implausible_values_are_clamped_with_a_note() -> None:
    reply = parse_priors({"objects": {"cutting board": {"mass_kg": -3, "friction": 9},
                                      "cardboard box": {"mass_kg": 400, "friction": 0.5}, "ghost": {"mass_kg": 1,
                                      "friction": 1}}})
    checked, notes = check_priors(reply, REQUEST)
    board, box = checked.objects["cutting board"], checked.objects["cardboard box"]
    assert board.mass_kg == pytest.approx(DENSITY_BOUNDS_KG_M3[0] * 0.35 * 0.25 * 0.02) and board.friction == 2.0
    assert box.mass_kg == MASS_BOUNDS_KG[1]  # 400 kg: beyond any tabletop object (density cap: 60 kg)
    assert "ghost" not in checked.objects
    assert len(notes) == 4 and any("cutting board.mass_kg -3 clamped" in n for n in notes)


@pytest.mark.parametrize(("raw", "message"), [
    ('{"objects": {"cutting board": {"mass_kg": NaN, "friction": 0.4}, "cardboard box": '
     '{"mass_kg": 1, "friction": 0.4}}}', "cutting board.mass_kg is nan"),
    ({"objects": {"cutting board": {"mass_kg": 1, "friction": 0.4}}}, "lacks: cardboard box"),
    ({"objects": {"cutting board": {"mass_kg": "heavy", "friction": 0.4}}}, "objects.cutting board.mass_kg"),
    ({"objects": [], "extra": 1}, "priors reply invalid"),
    ("no json here", "no JSON object"),
    (42, "must be a JSON object"),
])
def test_unusable_replies_are_one_clear_error(raw: object, message: str) -> None:
    with pytest.raises(BadReply, match=message):
        check_priors(parse_priors(raw), REQUEST)


_NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**30, 10**30),
                    st.sampled_from([0, -0.0, 1e-300, 1e300]))
_VALUE = st.recursive(st.one_of(st.none(), st.booleans(), _NUMBER, st.text(max_size=20)),
                      lambda inner: st.one_of(st.lists(inner, max_size=3),
                                              st.dictionaries(st.text(max_size=8), inner, max_size=3)), max_leaves=8)
_PRIOR = st.fixed_dictionaries({"mass_kg": _NUMBER, "friction": _NUMBER},
                               optional={"material": st.one_of(st.text(max_size=100), _VALUE), "junk": _VALUE})
_LABEL = st.one_of(st.sampled_from(["cutting board", "cardboard box"]), st.text(max_size=12))
_REPLY = st.one_of(
    st.fixed_dictionaries({"objects": st.dictionaries(_LABEL, st.one_of(_PRIOR, _VALUE), max_size=4)},
                          optional={"reasoning": st.one_of(st.text(max_size=50), _VALUE), "x": _VALUE}),
    st.dictionaries(st.text(max_size=10), _VALUE, max_size=3), _VALUE,
)


@pytest.mark.slow
@settings(max_examples=1200, derandomize=True, deadline=None)
@given(raw=_REPLY, as_text=st.booleans())
def test_hostile_replies_are_a_clear_error_or_bounded(raw: object, as_text: bool) -> None:
    try:
        text = json.dumps(raw) if as_text else raw
    except (TypeError, ValueError):
        text = raw
    try:
        checked, _ = check_priors(parse_priors(text), REQUEST)
    except ReasoningError as exc:
        assert 0 < len(str(exc)) <= 400
        return
    assert set(checked.objects) == {"cutting board", "cardboard box"}
    for obj in REQUEST.objects:
        p = checked.objects[obj.label]
        volume = math.prod(obj.size_m)
        assert max(DENSITY_BOUNDS_KG_M3[0] * volume, MASS_BOUNDS_KG[0]) - 1e-12 <= p.mass_kg
        assert p.mass_kg <= min(DENSITY_BOUNDS_KG_M3[1] * volume, MASS_BOUNDS_KG[1]) + 1e-12
        assert FRICTION_BOUNDS[0] <= p.friction <= FRICTION_BOUNDS[1]


# --- the role on both backends, recorded in the transcript ------------------------------------------

def test_priors_role_embedded_is_recorded() -> None:
    from kintsugi.reasoning import make_reasoner
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.methods.coral.priors import ask_priors
    from kintsugi.core.record import ReasonerSettings

    rec = RecordingReasoner(make_reasoner(ReasonerSettings()))
    reply, notes = ask_priors(rec, REQUEST)
    assert reply == embedded_priors(REQUEST) and notes == []
    assert [r.role for r in rec.records] == ["priors"] and rec.records[0].backend == "embedded"


def test_priors_role_over_the_openai_protocol_repairs_then_clamps() -> None:
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.reasoning.openai_backend import OpenAIReasoner
    from kintsugi.methods.coral.priors import ask_priors
    from tests.fake_openai_server import FakeOpenAIServer, content

    with FakeOpenAIServer() as server:
        server.push(content({"objects": {"cutting board": {"mass_kg": 1.2, "friction": 0.4, "material": "wood"}},
                             "reasoning": "forgot the box"}),
                    content({"objects": {"cutting board": {"mass_kg": 1.2, "friction": 0.4, "material": "wood"},
                                         "cardboard box": {"mass_kg": 900, "friction": 0.5, "material": "lead"}},
                             "reasoning": "a heavy box"}))
        model = OpenAIReasoner(model="fake-vlm", base_url=server.base_url, api_key_env="KINTSUGI_TEST_NO_SUCH_KEY")
        rec = RecordingReasoner(model)
        reply, notes = ask_priors(rec, REQUEST.model_copy(update={"image_png": b"\x89PNG\r\n\x1a\nfake"}))
        first, second = server.requests[0], server.requests[1]
    assert reply.objects["cutting board"].mass_kg == 1.2 and reply.objects["cardboard box"].mass_kg == 50.0
    assert notes and "cardboard box.mass_kg 900 clamped" in notes[0]
    assert "physics priors" in json.dumps(first["messages"][1]) and "manipulates objects on a table" in \
        first["messages"][0]["content"]
    assert "lacks: cardboard box" in json.dumps(second["messages"])  # the repair round quoted the problem
    assert rec.records[0].role == "priors" and rec.records[0].attempts == 2


def test_every_part_of_a_known_model_counts_toward_the_prior() -> None:
    """A board is told as its plate and its handle; the embedded prior weighs both (the plate alone is light)."""
    from kintsugi.methods.coral.types import PartView

    board = ObjectView(label="cutting board", size_m=(0.24, 0.18, 0.02),
                       parts=[PartView(size_m=(0.24, 0.18, 0.02)), PartView(size_m=(0.1, 0.05, 0.02), offset_m=(0.17, 0, 0))])
    plate = ObjectView(label="cutting board", size_m=(0.24, 0.18, 0.02))
    both = embedded_priors(PriorsRequest(task="pick the board", objects=[board])).objects["cutting board"]
    alone = embedded_priors(PriorsRequest(task="pick the board", objects=[plate])).objects["cutting board"]
    assert both.mass_kg == pytest.approx(alone.mass_kg * (0.24 * 0.18 + 0.1 * 0.05) / (0.24 * 0.18), rel=1e-3)
