"""CoRAL's controlled instruction language: words -> steps (docs/coral-language.md).

An instruction is a sequence of clauses (split at `then`, `and then`, `,`, `;`, `.`, or `and` before a verb). Each
clause is an imperative: an optional negation (`don't`, `do not`, `never`), a verb phrase, an object phrase, and
modifiers (targets, directions, distances, forces, durations, a part, an orientation, a fixture to use). A clause
without a verb (`using the curb as a fixture`) adds its modifiers to the clause before it.

Nouns come from the scene as the robot perceives it: each object's name, label words, shape, colour and
material, each fixture's and marker's name and label, plus the table, its edge and the robot. Every word must be
read: anything else raises `NotUnderstood` naming the words, so nothing is skipped silently.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from kintsugi.methods.coral.nouns import Entity, Lexicon, NotUnderstood, plural_base
from kintsugi.methods.coral.types import FormulationRequest

VERBS: dict[tuple[str, ...], str] = {
    ("pick", "up"): "pick", ("pick",): "pick", ("lift",): "pick", ("raise",): "pick", ("grab",): "pick",
    ("grasp",): "pick", ("take",): "pick", ("picking",): "pick", ("lifting",): "pick", ("grabbing",): "pick",
    ("put", "down"): "place", ("put",): "place", ("place",): "place", ("set", "down"): "place", ("set",): "place",
    ("move",): "place", ("carry",): "place", ("bring",): "place", ("putting",): "place", ("placing",): "place",
    ("moving",): "place",
    ("push",): "push", ("shove",): "push", ("slide",): "push", ("nudge",): "push", ("pushing",): "push",
    ("sliding",): "push", ("keep", "pushing"): "push", ("roll",): "push", ("rolling",): "push",
    ("press",): "press", ("keep", "pressing"): "press", ("pressing",): "press", ("keep", "pushing", "on"): "press",
    ("flip",): "flip", ("tip",): "flip", ("topple",): "flip", ("knock",): "flip", ("turn", "over"): "flip",
    ("flipping",): "flip", ("tipping",): "flip", ("toppling",): "flip", ("knocking",): "flip",
    ("hold", "still"): "hold", ("wait",): "hold", ("stay", "still"): "hold", ("keep", "still"): "hold",
    ("touch",): "touch", ("touching",): "touch",
}
"""Verb phrases -> the step's verb. `touch` exists only to be forbidden ("don't touch the cubes")."""
PARTICLES = {"pick": {"up"}, "place": {"down"}, "flip": {"over", "up"}, "push": set(), "press": set(), "hold": set(),
             "touch": set()}
NEGATIONS = (("do", "not"), ("never",), ("dont",))
FILLERS = frozenset({"please", "now", "first", "next", "finally", "also", "afterwards", "then"})
SPLIT_WORDS = (("and", "then"), ("after", "that"), ("but", "then"), ("then",), ("but",))
CONTINUE_WORDS = frozenset({"using", "with", "against", "for", "until", "so", "by", "toward", "towards", "to",
                            "away", "onto", "on", "without", "left", "right", "forward", "forwards", "back",
                            "backward", "backwards", "over", "past"})
NUMBER_WORDS = {"one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9,
                "ten": 10, "eleven": 11, "twelve": 12, "fifteen": 15, "twenty": 20, "half": 0.5}
LENGTH = {"m": 1.0, "metre": 1.0, "metres": 1.0, "meter": 1.0, "meters": 1.0, "cm": 0.01, "centimetre": 0.01,
          "centimetres": 0.01, "centimeter": 0.01, "centimeters": 0.01, "mm": 0.001, "millimetre": 0.001,
          "millimetres": 0.001, "millimeter": 0.001, "millimeters": 0.001}
FORCE = {"n": 1.0, "newton": 1.0, "newtons": 1.0}
TIME = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0}
DIRECTIONS = {"left": "left", "leftward": "left", "leftwards": "left", "right": "right", "rightward": "right",
              "rightwards": "right", "forward": "forward", "forwards": "forward", "ahead": "forward",
              "back": "back", "backward": "back", "backwards": "back", "front": "forward"}
"""In the robot's frame: forward = away from it (+x), back = toward it, left = +y, right = -y."""
ORIENT = {"side": "side", "end": "end", "back": "side", "top": "side"}
LANGUAGE_WORDS = frozenset({w for k in VERBS for w in k} | set(FILLERS) | set(CONTINUE_WORDS) | set(NUMBER_WORDS)
                           | set(LENGTH) | set(FORCE) | set(TIME) | set(DIRECTIONS) | set(ORIENT) | {
    "the", "a", "an", "its", "it", "up", "down", "over", "of", "as", "that", "lies", "stands", "sticks", "out",
    "until", "from", "among", "between", "off", "into", "in", "at", "force", "constant", "steady", "help",
    "pivot", "fixture", "stop", "edge", "table", "do", "not", "never", "dont", "and", "then", "after", "touches",
    "hits", "reaches", "meets", "is", "overhangs", "hangs", "beyond", "past", "them", "itself"})


@dataclass
class Step:
    """One clause read: what to do to which object, and how."""

    verb: str
    obj: str | None = None
    negated: bool = False
    relation: str | None = None
    """against / toward / away / onto / over-edge."""
    target: Entity | None = None
    direction: str | None = None
    distance_m: float | None = None
    force_n: float | None = None
    duration_s: float | None = None
    part: str | None = None
    orient: str | None = None
    using: str | None = None
    words: str = ""
    said: str = ""
    """The verb as said (`roll`, `slide`, ...)."""
    notes: list[str] = field(default_factory=list)


def tokens(text: str) -> list[str]:
    t = text.lower().replace("\u2019", "'").replace("n't", " not").replace("'s", "")
    t = re.sub(r"(\d)([a-z])", r"\1 \2", t)
    return re.findall(r"\d+(?:\.\d+)?|[a-z]+|[,;.]", t)


def clauses(toks: list[str], verbs: set[str]) -> list[list[str]]:
    out: list[list[str]] = [[]]
    i = 0
    while i < len(toks):
        w = toks[i]
        hit = next((s for s in SPLIT_WORDS if tuple(toks[i:i + len(s)]) == s), None)
        if w in ",;." or hit or (w == "and" and i + 1 < len(toks) and (toks[i + 1] in verbs or toks[i + 1] in
                                                                            ("do", "dont", "never", "keep"))):
            i += len(hit) if hit else 1
            out.append([])
            continue
        out[-1].append(w)
        i += 1
    return [c for c in out if c]


class Reader:
    """Reads one instruction over one scene's lexicon into steps."""

    def __init__(self, req: FormulationRequest) -> None:
        self.lex = Lexicon.of(req)
        self.last: str | None = None
        self._obj: str | None = None
        self._pending: list[Step] = []

    def read(self, text: str) -> list[Step]:
        verbs = {k[0] for k in VERBS}
        steps: list[Step] = []
        for c in clauses(tokens(text), verbs):
            step = self._clause(c, steps[-1] if steps else None)
            if step is not None:
                steps.append(step)
            steps.extend(self._pending)
        if not steps:
            raise NotUnderstood("not understood: the instruction has no step (e.g. 'push the box against the wall')")
        return steps

    # --- one clause ---------------------------------------------------------------------------------------------
    def _clause(self, c: list[str], prev: Step | None) -> Step | None:
        self._pending: list[Step] = []
        words = " ".join(c)
        i = 0
        while i < len(c) and c[i] in FILLERS:
            i += 1
        negated = False
        for neg in NEGATIONS:
            if tuple(c[i:i + len(neg)]) == neg:
                negated, i = True, i + len(neg)
                break
        verb, n = self._verb(c, i)
        if verb is None:
            if c[i:] and c[i] in CONTINUE_WORDS and prev is not None and not negated:
                self._modifiers(c, i, prev, words)
                prev.words += ", " + words
                return None
            raise NotUnderstood(f"not understood: {words!r}: no verb the language knows "
                                "(pick up, put, push, slide, press, flip, tip, hold still)")
        step = Step(verb=verb, negated=negated, words=words, said=c[i])
        self._modifiers(c, i + n, step, words)
        if step.obj is None and verb != "hold":
            if self.last is None:
                raise NotUnderstood(f"not understood: {words!r}: which object? (the scene holds "
                                    f"{self.lex.describe()})")
            step.obj = self.last
        if step.obj is not None:
            self.last = step.obj
        return step

    def _verb(self, c: list[str], i: int) -> tuple[str | None, int]:
        for n in (3, 2, 1):
            v = VERBS.get(tuple(c[i:i + n]))
            if v is not None:
                return v, n
        return None, 0

    def _modifiers(self, c: list[str], i: int, step: Step, words: str) -> None:
        unread: list[str] = []
        while i < len(c):
            j = self._modifier(c, i, step)
            if j > i:
                i = j
                continue
            unread.append(c[i])
            i += 1
        if unread:
            strange = [w for w in unread if w not in self.lex.vocab and w not in LANGUAGE_WORDS
                       and not re.fullmatch(r"[\d.]+", w)]
            hint = (f"; {', '.join(repr(w) for w in dict.fromkeys(strange))} is neither a word of the language nor "
                    f"a name in the scene (it holds {self.lex.describe()})") if strange else ""
            raise NotUnderstood(f"not understood: {' '.join(unread)!r} in {words!r}{hint}")

    def _number(self, c: list[str], i: int, units: dict[str, float]) -> tuple[float | None, int]:
        if i >= len(c):
            return None, i
        w = c[i]
        value = float(w) if re.fullmatch(r"\d+(?:\.\d+)?", w) else NUMBER_WORDS.get(w)
        if value is None or i + 1 >= len(c) or c[i + 1] not in units:
            return None, i
        return value * units[c[i + 1]], i + 2

    def _np(self, c: list[str], i: int) -> tuple[Entity | None, int]:
        return self.lex.phrase(c, i, self._obj or self.last)

    def _modifier(self, c: list[str], i: int, s: Step) -> int:  # noqa: C901 - one table of phrase forms
        self._obj = s.obj
        w = c[i]
        at = lambda *seq: tuple(c[i:i + len(seq)]) == seq  # noqa: E731
        if w in PARTICLES.get(s.verb, set()):
            if w == "over" and s.verb == "flip":
                s.orient = s.orient or "side"
            return i + 1
        # object phrase (the step's object), if none yet
        if s.obj is None:
            e, j = self._np(c, i)
            if e is not None and (e.kind == "object" or (e.kind in ("group", "fixture") and s.negated)):
                s.obj = e.name
                return j
            if e is not None and e.kind == "group":
                raise NotUnderstood(f"not understood: {' '.join(c[i:j])!r} names {e.name.replace(',', ', ')}: "
                                    "one object per step")
        for a in ("a", "an", "the"):
            if at("with", a, "force", "of") or at("with", a, "constant", "force", "of") or \
                    at("with", a, "steady", "force", "of") or at("at", a, "force", "of"):
                k = i + 4 + (c[i + 2] in ("constant", "steady"))
                f, j = self._number(c, k, FORCE)
                if f is not None:
                    s.force_n = f
                    return j
        if w in ("with", "at"):
            f, j = self._number(c, i + 1, FORCE)
            if f is not None:
                s.force_n = f
                return j
        f, j = self._number(c, i, FORCE)
        if f is not None:
            s.force_n = f
            return j
        if w == "for":
            d, j = self._number(c, i + 1, TIME)
            if d is not None:
                s.duration_s = d
                return j
        if w == "by":
            d, j = self._number(c, i + 1, LENGTH)
            if d is not None:
                s.distance_m = d
                return j
            if i + 2 < len(c) and c[i + 1] in ("its", "the"):
                s.part = plural_base(c[i + 2])
                return i + 3
        d, j = self._number(c, i, LENGTH)
        if d is not None:
            s.distance_m = d
            return j
        # directions
        if w in DIRECTIONS and not (w == "back" and s.verb == "place"):
            s.direction = DIRECTIONS[w]
            return i + 1
        if at("to", "the") and i + 2 < len(c) and c[i + 2] in DIRECTIONS:
            s.direction = DIRECTIONS[c[i + 2]]
            return i + 3
        if w in ("toward", "towards", "away") or at("away", "from"):
            k = i + 1 + (w == "away" and at("away", "from"))
            e, j = self._np(c, k)
            if e is not None and e.kind == "robot":
                s.direction = "forward" if w == "away" else "back"
                return j
            if e is not None:
                s.relation, s.target = ("away" if w == "away" else "toward"), e
                return j
        # orientation goals
        for form in (("so", "that", "it", "lies", "on", "its"), ("so", "it", "lies", "on", "its"),
                     ("so", "that", "it", "stands", "on", "its"), ("so", "it", "stands", "on", "its"),
                     ("onto", "its"), ("on", "its"), ("on", "to", "its")):
            if at(*form) and i + len(form) < len(c) and c[i + len(form)] in ORIENT:
                s.orient = ORIENT[c[i + len(form)]]
                return i + len(form) + 1
        # the table edge
        for form in (("until", "its"), ("until", "it"), ("until", "the")):
            if at(*form):
                k = i + len(form)
                if form[1] in ("its", "the") and k < len(c) and c[k] not in ("sticks", "overhangs"):
                    s.part = plural_base(c[k])
                    k += 1
                for tail in (("sticks", "out", "over"), ("sticks", "out", "past"), ("overhangs",),
                             ("hangs", "over"), ("sticks", "out", "beyond")):
                    if tuple(c[k:k + len(tail)]) == tail:
                        e, j = self._np(c, k + len(tail))
                        if e is not None and e.kind == "edge":
                            s.relation, s.target = "over-edge", e
                            return j
                for tail in (("touches",), ("hits",), ("reaches",), ("meets",), ("is", "against"), ("is", "on")):
                    if tuple(c[k:k + len(tail)]) == tail:
                        e, j = self._np(c, k + len(tail))
                        if e is not None:
                            s.relation, s.target = ("onto" if e.kind == "marker" else "against"), e
                            return j
        if w in ("over", "past", "off", "beyond"):
            e, j = self._np(c, i + 1)
            if e is not None and e.kind == "edge":
                s.relation, s.target = "over-edge", e
                return j
        # fixtures to use
        if w == "using" or at("with", "the", "help", "of"):
            e, j = self._np(c, i + 1 if w == "using" else i + 4)
            if e is not None and e.kind == "fixture":
                s.using = e.name
                for tail in (("as", "a", "fixture"), ("as", "a", "stop"), ("as", "a", "pivot"),
                             ("to", "pivot", "it", "against"), ("to", "pivot", "against"), ("to", "pivot", "on")):
                    if tuple(c[j:j + len(tail)]) == tail:
                        j += len(tail)
                return j
        # targets
        if w in ("against", "to", "onto", "on", "into", "in", "toward", "towards") or at("on", "to") \
                or at("on", "top", "of"):
            k = i + (3 if at("on", "top", "of") else 2 if at("on", "to") else 1)
            e, j = self._np(c, k)
            if e is not None and e.kind in ("fixture", "marker", "object", "edge"):
                rel = {"against": "against", "toward": "toward", "towards": "toward"}.get(w, "onto")
                if e.kind == "fixture" and rel == "onto":
                    rel = "against" if w == "to" else "onto"
                if e.kind == "edge":
                    rel = "over-edge" if w == "to" else rel
                s.relation, s.target = rel, e
                return j
        # where the object is now (a check, not a target)
        if w == "from" or at("off", "the", "table") or at("up", "from"):
            k = i + (1 if w == "from" else 2 if at("up", "from") else 1)
            if c[k:k + 1] == ["among"] or c[k:k + 1] == ["between"]:
                k += 1
            e, j = self._np(c, k)
            if e is not None and e.kind in ("table", "object", "group", "fixture", "marker") and e.name != s.obj:
                return j
        if w == "without" and i + 1 < len(c):
            verb, n = self._verb(c, i + 1)
            if verb is not None:
                e, j = self._np(c, i + 1 + n)
                obj = e.name if e is not None and e.kind in ("object", "group", "fixture") else s.obj
                self._pending.append(Step(verb=verb, obj=obj, negated=True, words=" ".join(c[i:j])))
                return j
        return i


def read_instruction(req: FormulationRequest) -> list[Step]:
    """The request's instruction as steps over its scene; NotUnderstood outside the language."""
    return Reader(req).read(req.task)


__all__ = ["NotUnderstood", "Reader", "Step", "read_instruction", "tokens"]
