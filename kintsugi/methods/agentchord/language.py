"""The controlled language of AgentChord instructions: words -> clauses (docs/agentchord-language.md).

A recursive-descent parser over a per-scene lexicon: the scene's objects (their name words, kind words and
colour), its arms and regions are the nouns, a fixed set of verbs, particles and prepositions the rest. Each
clause is one imperative (`put the blue block on the plate with the left arm`); `reading.py` turns the
clauses into the formal goal. Anything outside the language raises `NotUnderstood`, naming the words it
could not read; nothing is skipped silently.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from kintsugi.methods.agentchord.symbolic import PlanningError

COLOURS = frozenset("red green blue yellow orange purple pink white black grey gray brown".split())
SYNONYMS = {"cube": "block", "brick": "block", "mug": "cup", "flask": "bottle", "pod": "capsule", "dish": "plate",
            "bin": "tray", "basin": "bowl", "cloth": "towel", "gray": "grey", "towards": "toward", "onto": "on",
            "inside": "into"}
COMPOUNDS = {("coffee", "capsule"): "capsule", ("water", "bottle"): "bottle", ("dinner", "plate"): "plate",
             ("next", "to"): "beside", ("on", "top", "of"): "on", ("let", "go", "of"): "release",
             ("let", "go"): "release", ("in", "front"): "forward", ("at", "the", "front"): "forward"}
VERBS = {"pick": "take", "grasp": "take", "grab": "take", "take": "take", "lift": "take", "raise": "take",
         "hold": "take", "keep": "take", "get": "take",
         "put": "place", "place": "place", "set": "place", "move": "place", "bring": "place", "lay": "place",
         "return": "place", "carry": "place", "stand": "place", "stack": "place", "leave": "place",
         "pour": "pour", "hand": "handover", "pass": "handover", "give": "handover", "release": "release",
         "fold": "fold", "use": "use"}
NEG_VERBS = {"move": "moved", "moving": "moved", "drop": "dropped", "dropping": "dropped", "tip": "tipped",
             "tipping": "tipped", "knock": "tipped", "knocking": "tipped", "topple": "tipped", "toppling": "tipped",
             "tilt": "tipped", "tilting": "tipped"}
ARM_WORDS = frozenset({"arm", "arms", "hand", "hands", "gripper", "grippers"})
REGION_NOUNS = frozenset({"region", "area", "zone", "target", "patch", "spot"})
REGION_COLOUR = "green"
"""Target regions are painted green on the table; no other colour names a region."""
DETERMINERS = frozenset({"the", "a", "an", "this", "that"})
CONNECTIVES = frozenset({"and", "then", "finally", "next", "first", "now", "afterwards"})
SUBSTANCES = frozenset({"water", "liquid", "juice", "coffee", "tea", "milk", "some"})


class NotUnderstood(PlanningError):
    """The instruction is outside the controlled language; the message says which words."""


@dataclass(frozen=True)
class Thing:
    """An object of the scene as the language may name it."""

    name: str
    words: frozenset[str]
    """Name words (`red_block` -> red, block), kind words and perceived colour."""
    stands: bool | None = None
    """Seen standing on a base (a bottle, a cup); None: unknown."""


@dataclass(frozen=True)
class Scene:
    things: tuple[Thing, ...]
    arms: tuple[str, ...] = ("left", "right")
    regions: tuple[str, ...] = ()
    """Named fixed regions of the task statement (`target` is the one painted region when there is one)."""
    directions: tuple[str, ...] = ("away", "toward", "leftward", "rightward")

    @staticmethod
    def of(names: list[str] | tuple[str, ...], arms=("left", "right"), regions=(), directions=None,  # noqa: ANN001
           kinds: dict | None = None, colours: dict | None = None, stands: dict | None = None) -> "Scene":
        things = []
        for n in names:
            words = set(re.split(r"[_\s]+", n.lower())) | set((kinds or {}).get(n, "").lower().split())
            if (colours or {}).get(n):
                words.add(SYNONYMS.get(colours[n].lower(), colours[n].lower()))
            things.append(Thing(n, frozenset(SYNONYMS.get(w, w) for w in words if w), (stands or {}).get(n)))
        return Scene(tuple(things), tuple(arms), tuple(regions),
                     tuple(directions) if directions is not None else Scene.directions)


@dataclass
class Group:
    """One object phrase with what is said about it in a clause."""

    objects: list[str] = field(default_factory=list)
    particles: set[str] = field(default_factory=set)
    orient: str | None = None
    place: tuple | None = None
    """("table",), ("on", y), ("into", y), ("region", r), ("left_of", y), ("right_of", y), ("beside", y)."""
    side_of: str | None = None
    """`along the plate's side`: the placement is the spot alongside that object's side."""
    arms: tuple[str, ...] = ()
    heading: str | None = None
    without: list[tuple[str, str]] = field(default_factory=list)
    source: str | None = None
    to_arm: str | None = None
    rims: bool = False


@dataclass
class Clause:
    verb: str
    words: str
    groups: list[Group] = field(default_factory=list)
    negated: tuple[str, list[str]] | None = None
    uses: list[tuple[tuple[str, ...], str | None]] = field(default_factory=list)


def tokens(text: str) -> list[str]:
    text = text.lower().replace("n't", " not").replace("-", " ").replace("\u2019", "'")
    raw = re.findall(r"[a-z]+|'s|[,.;:!()]|\S", text)
    out: list[str] = []
    i = 0
    while i < len(raw):
        for words, one in COMPOUNDS.items():
            if tuple(raw[i:i + len(words)]) == words:
                out.append(one)
                i += len(words)
                break
        else:
            out.append(SYNONYMS.get(raw[i], raw[i]))
            i += 1
    return out
