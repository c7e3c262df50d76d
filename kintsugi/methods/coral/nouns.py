"""The nouns of CoRAL's instruction language: what the scene holds, as the robot perceives it.

Objects are named by their name, label words, shape, colour and material (`the wooden cylinder`, `the green
box`); fixtures and markers by name and label (`the wall`, `the curb`, `the green disc`, `the goal`); besides
them the table, its edge, and the robot. A colour or material the robot was not told for an object is accepted
only when the rest of the phrase names exactly one thing, and the reading says so (a note).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from kintsugi.methods.coral.types import FormulationRequest

COLOURS = frozenset("red green blue yellow orange purple pink white black grey gray brown cyan".split())
MATERIALS = frozenset("wooden wood steel metal metallic plastic foam rubber cardboard paper glass ceramic".split())
SHAPES = frozenset("box cube cylinder sphere ball capsule puck board block can disc".split())
SYNONYMS = {"crate": "box", "brick": "block", "gray": "grey", "wood": "wooden", "metal": "steel",
            "metallic": "steel", "towards": "toward", "ball": "sphere", "tin": "can"}
MARKER_NOUNS = frozenset({"disc", "disk", "marker", "goal", "target", "circle", "spot", "region", "area", "mark"})
FIXTURE_NOUNS = frozenset({"fixture", "stop"})
ROBOT_NOUNS = frozenset({"robot", "you", "me", "yourself", "arm"})
DETERMINERS = frozenset({"the", "a", "an", "its", "this", "that", "their", "your"})
FUNCTION_WORDS = frozenset({"the", "a", "an", "its", "it", "of", "to", "on", "onto", "into", "in", "from", "by",
                            "with", "at", "for", "and", "then", "up", "down", "over", "against", "toward", "away",
                            "until", "using", "so", "that", "not", "do", "without", "off", "past", "as", "among"})
STATE_TALL = frozenset({"standing", "tall", "upright"})
STATE_FLAT = frozenset({"flat", "lying"})


class NotUnderstood(ValueError):
    """The instruction is outside the controlled language, or names nothing the scene holds."""


def plural_base(w: str) -> str:
    w = SYNONYMS.get(w, w)
    return w


@dataclass(frozen=True)
class Entity:
    kind: str
    """object, group, fixture, marker, table, edge, robot."""
    name: str
    words: frozenset[str] = frozenset()
    unknown: frozenset[str] = frozenset()
    """Attribute words the robot was not told for it (its colour or material when unknown)."""
    near: frozenset[str] = frozenset()
    """Colour words next to its perceived colour (an orange-looking board may be called brown): they match only
    when no thing in the scene matches exactly."""


def _split(text: str) -> set[str]:
    return {SYNONYMS.get(w, w) for w in re.findall(r"[a-z]+", re.sub(r"\d+", " ", text.lower()))}


NEAR_COLOURS = {"orange": {"brown", "red", "yellow"}, "brown": {"orange", "red"}, "red": {"orange", "pink"},
                "yellow": {"orange"}, "pink": {"red", "purple"}, "purple": {"pink", "blue"}, "blue": {"cyan", "purple"},
                "cyan": {"blue", "green"}, "green": {"cyan"}, "grey": {"white", "black"}, "white": {"grey"},
                "black": {"grey"}}
"""Colours a person may call a perceived colour (camera hue buckets are coarse)."""


def _near(words: set[str]) -> frozenset[str]:
    return frozenset(x for c in words & COLOURS for x in NEAR_COLOURS.get(c, ()))


def _unknown(words: set[str]) -> frozenset[str]:
    """The attribute words not told for a thing: every colour when its words hold none, every material likewise."""
    return frozenset((COLOURS if not words & COLOURS else set()) | (MATERIALS if not words & MATERIALS else set()))


class Lexicon:
    def __init__(self, entities: list[Entity], unlabelled: frozenset[str] = frozenset()) -> None:
        self.entities = entities
        self.unlabelled = unlabelled
        """Objects the scene gives no label (their label is their name): one word before their noun is read as
        part of the label they were not given, with a note."""
        self.notes: list[str] = []
        self.vocab = set().union(*(e.words for e in entities), COLOURS, MATERIALS, STATE_TALL, STATE_FLAT)

    @staticmethod
    def of(req: FormulationRequest) -> "Lexicon":
        out = []
        for o in req.objects:
            w = _split(o.name) | _split(o.label) | _split(o.shape)
            w |= _split(o.colour) | _split(o.material)
            tall = o.size_m[2] > max(o.size_m[0], o.size_m[1]) and o.upright_deg < 30
            w |= STATE_TALL if tall else STATE_FLAT
            w |= {"object", "thing", "item"}
            if (o.shape or "box") == "box":
                w.add("block")
                if max(o.size_m) < 1.25 * min(o.size_m):
                    w.add("cube")
            out.append(Entity("object", o.name, frozenset(w), _unknown(w), _near(w)))
        for f in req.fixtures:
            w = _split(f.name) | _split(f.label) | FIXTURE_NOUNS
            out.append(Entity("fixture", f.name, frozenset(w), _unknown(w), _near(w)))
        for m in req.markers:
            w = _split(m.name) | _split(m.label) | MARKER_NOUNS
            out.append(Entity("marker", m.name, frozenset(w), _unknown(w) - MATERIALS, _near(w)))
        out += [Entity("table", "table", frozenset({"table"})),
                Entity("edge", "edge", frozenset({"edge", "table", "front"})),
                Entity("robot", "robot", ROBOT_NOUNS)]
        return Lexicon(out, frozenset(o.name for o in req.objects if o.label.strip().lower() == o.name.lower()))

    def _base(self, w: str) -> str:
        w = SYNONYMS.get(w, w)
        if w in self.vocab:
            return w
        for cut in (1, 2):
            if w.endswith("es"[-cut:]) and SYNONYMS.get(w[:-cut], w[:-cut]) in self.vocab:
                return SYNONYMS.get(w[:-cut], w[:-cut])
        return w

    def _known(self, w: str) -> bool:
        return self._base(w) in self.vocab

    def describe(self) -> str:
        return ", ".join(f"{e.name}" for e in self.entities if e.kind in ("object", "fixture", "marker"))

    def phrase(self, c: list[str], i: int, last: str | None) -> tuple[Entity | None, int]:
        """The noun phrase at c[i] (None when there is none); NotUnderstood when it names nothing or several."""
        if i >= len(c):
            return None, i
        if c[i] in ("it", "itself", "them"):
            if last is None:
                raise NotUnderstood(f"not understood: {c[i]!r} refers to nothing named before it")
            return Entity("object", last), i + 1
        j = i + (c[i] in DETERMINERS)
        words: list[str] = []
        guessed: list[str] = []
        while j < len(c) and (self._known(c[j]) or (j + 1 < len(c) and self._known(c[j + 1]) and j > i
                                                     and c[i] in DETERMINERS and c[j] not in FUNCTION_WORDS)):
            if not self._known(c[j]):
                guessed.append(c[j])
            else:
                words.append(c[j])
            j += 1
        if tuple(c[j:j + 3]) == ("of", "the", "table") and words and words[-1] == "edge":
            words.append("table")
            j += 3
        if not words:
            return None, i
        plural = False
        want = []
        for w in words:
            base = self._base(w)
            plural = plural or base != SYNONYMS.get(w, w)
            want.append(base)
        noun = want[-1]
        found = [e for e in self.entities if noun in e.words and all(x in e.words or x in e.unknown for x in want)]
        if not found:
            found = [e for e in self.entities if noun in e.words
                     and all(x in e.words or x in e.unknown or x in e.near for x in want)]
        if "edge" in want:
            found = [e for e in found if e.kind == "edge"]
        elif any(e.kind == "table" for e in found):
            found = [e for e in found if e.kind == "table"]
        elif any(e.kind in ("object", "fixture", "marker") for e in found):
            found = [e for e in found if e.kind in ("object", "fixture", "marker")]
        phrase = " ".join(c[i:j])
        if not found:
            raise NotUnderstood(f"not understood: nothing in the scene is {phrase!r} (it holds {self.describe()})")
        if plural:
            if any(e.kind != "object" for e in found):
                raise NotUnderstood(f"not understood: {phrase!r}: only objects can be named in the plural")
            return Entity("group", ",".join(e.name for e in found), frozenset(want)), j
        if len(found) > 1:
            raise NotUnderstood(f"not understood: {phrase!r} could be any of {', '.join(e.name for e in found)}: "
                                "say which (by its name, colour or material)")
        told = [x for x in want if x in found[0].unknown and x not in found[0].words]
        if told:
            self.notes.append(f"{' and '.join(told)} is not perceived for {found[0].name}: {phrase!r} is read as "
                              f"{found[0].name}, the only match of the rest of it")
        if guessed:
            if found[0].kind != "object" or found[0].name not in self.unlabelled:
                raise NotUnderstood(f"not understood: {' '.join(guessed)!r} in {phrase!r} is neither a word of the "
                                    f"language nor a name in the scene (it holds {self.describe()})")
            self.notes.append(f"{' '.join(guessed)!r} in {phrase!r} is read as part of {found[0].name}'s label "
                              "(the scene gives it no label)")
        return found[0], j


def colour_name(rgba: tuple[float, ...]) -> str:
    """The colour word a camera would give an object of this RGBA (hue buckets; greys by lightness)."""
    import colorsys

    r, g, b = (max(0.0, min(1.0, float(x))) for x in rgba[:3])
    h, l, s = colorsys.rgb_to_hls(r, g, b)
    if s < 0.2 or max(r, g, b) - min(r, g, b) < 0.12:
        return "white" if l > 0.8 else "black" if l < 0.2 else "grey"
    hue = h * 360
    for bound, name in ((15, "red"), (45, "orange"), (70, "yellow"), (160, "green"), (200, "cyan"), (255, "blue"),
                        (290, "purple"), (345, "pink"), (360, "red")):
        if hue < bound:
            return "brown" if name == "orange" and l < 0.35 else name
    return "red" if not math.isnan(hue) else "grey"


__all__ = ["COLOURS", "Entity", "Lexicon", "MATERIALS", "NotUnderstood", "colour_name", "plural_base"]
