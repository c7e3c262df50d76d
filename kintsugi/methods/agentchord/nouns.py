"""Cursor and nouns of the controlled language's parser: objects (by name, kind, colour, `it`, `them`, `both`),
arms, regions and directions, resolved against the scene."""

from __future__ import annotations

from kintsugi.methods.agentchord.language import (ARM_WORDS, COLOURS, DETERMINERS, REGION_COLOUR, REGION_NOUNS,
                                                  NotUnderstood, Scene, tokens)


class Nouns:
    """Tokens and a cursor; `mentions` keeps the objects in the order they were named (for `it`, `them`)."""

    def __init__(self, text: str, scene: Scene) -> None:
        self.text, self.scene = text, scene
        self.t = tokens(text)
        self.i = 0
        self.mentions: list[str] = []
        self.last_main: list[str] = []
        self.clauses: list = []
        self.current: list[str] = []
        self.lexicon = frozenset().union(*(th.words for th in scene.things)) if scene.things else frozenset()

    # --- cursor -------------------------------------------------------------------------------------
    def peek(self, k: int = 0) -> str:
        return self.t[self.i + k] if self.i + k < len(self.t) else ""

    def eat(self, *words: str) -> bool:
        if tuple(self.t[self.i:self.i + len(words)]) == words:
            self.i += len(words)
            return True
        return False

    def rest(self) -> str:
        end = self.i
        while end < len(self.t) and self.t[end] not in ",.;:!":
            end += 1
        return " ".join(self.t[self.i:end]) or "(end of the instruction)"

    def fail(self, why: str) -> NotUnderstood:
        return NotUnderstood(f"not understood: {self.rest()!r}: {why}")

    def at_boundary(self) -> bool:
        return self.peek() in ("", ",", ".", ";", ":", "!", "then")

    def object_ahead(self) -> bool:
        k = 1 if self.peek() in DETERMINERS else 0
        return self.peek(k) in self.lexicon | COLOURS | {"it", "them", "one"} or (
            k == 0 and self.peek() == "both" and self.peek(1) not in ARM_WORDS)

    def object_ahead_at(self, k: int) -> bool:
        save = self.i
        self.i += k
        try:
            return self.object_ahead()
        finally:
            self.i = save

    def direction(self) -> str | None:
        if self.eat("away"):
            if self.eat("from"):
                self.eat("the") or self.eat("your")
                if not (self.eat("you") or self.eat("robot") or self.eat("me") or self.eat("us")):
                    raise self.fail("'away from' takes you or the robot")
            d = "away"
        elif self.eat("toward"):
            self.eat("the")
            if not (self.eat("you") or self.eat("robot") or self.eat("me") or self.eat("us")):
                raise self.fail("'toward' takes you or the robot")
            d = "toward"
        elif self.eat("to", "the", "left") or self.eat("left"):
            d = "leftward"
        elif self.eat("to", "the", "right") or self.eat("right"):
            d = "rightward"
        else:
            return None
        if d not in self.scene.directions:
            raise self.fail(f"the action library has no heading {d!r}")
        return d

    # --- nouns ------------------------------------------------------------------------------------
    def region_ahead(self, k: int) -> bool:
        j = self.i + k
        while j < len(self.t) and (self.t[j] in DETERMINERS or self.t[j] in COLOURS or self.t[j] == "painted"):
            j += 1
        return j < len(self.t) and self.t[j] in REGION_NOUNS | {"forward"}

    def region(self) -> str:
        words = []
        while self.peek() in DETERMINERS | COLOURS | REGION_NOUNS | {"painted", "forward"}:
            words.append(self.peek())
            self.i += 1
        if self.eat("of", "the", "table"):
            pass
        for w in words:
            if w in COLOURS and w != REGION_COLOUR:
                raise self.fail(f"regions of the table are painted {REGION_COLOUR}; '{w}' names none")
        regions = [r for r in self.scene.regions]
        if not regions:
            raise NotUnderstood(f"not understood: {' '.join(words)!r}: the task statement names no region")
        said = set(words)
        score = {r: len(said & set(r.split("_"))) for r in regions}
        best = max(score.values())
        top = [r for r in regions if score[r] == best]
        if best == 0:
            real = [r for r in regions if r != "target"]
            top = real if len(real) == 1 else (["target"] if "target" in regions else regions)
        if len(top) > 1:
            raise NotUnderstood(f"not understood: {' '.join(words)!r} could be region {' or '.join(top)}")
        return top[0]

    def arm_phrase(self) -> tuple[str, ...] | None:
        save = self.i
        self.eat("the") or self.eat("its") or self.eat("your") or self.eat("his")
        if self.peek() in ("both", "two") and self.peek(1) in ARM_WORDS:
            self.i += 2
            return self._arms(("left", "right"))
        sides = []
        while self.peek() in ("left", "right"):
            sides.append(self.peek())
            self.i += 1
            if self.peek() in ARM_WORDS:
                self.i += 1
                break
            if self.eat("and") or self.eat("and", "the"):
                self.eat("the")
                continue
            self.i = save
            return None
        if sides and self.t[self.i - 1] in ARM_WORDS:
            return self._arms(tuple(dict.fromkeys(sides)))
        self.i = save
        return None

    def _arms(self, arms: tuple[str, ...]) -> tuple[str, ...]:
        for a in arms:
            if a not in self.scene.arms:
                raise self.fail(f"the robot has no {a} arm here (arms: {', '.join(self.scene.arms)})")
        return arms

    def noun_phrase(self, required: bool = False, reflexive: list[str] | None = None,
                    coordinate: bool = False, main: bool = False) -> list[str]:
        """An object phrase -> the objects it names. `it` as a step's own object is the previous step's object
        ("take the bottle, pour from it into the cup, then put it back"); elsewhere ("into it", "right of it")
        the object named last that this phrase is not about."""
        p = self.peek()
        if p == "it":
            self.i += 1
            if main and not reflexive and len(self.last_main) == 1:
                return self._mention(list(self.last_main))
            return self._mention([self._it(reflexive)])
        if p == "them" or self.eat("both", "of", "them") or self.eat("each", "of", "them") or p == "both":
            self.i += p in ("them", "both")
            return self._mention(self._them(p))
        start = self.i
        self.eat("the") or self.eat("a") or self.eat("an") or self.eat("this") or self.eat("that")
        words = []
        while self.peek() in self.lexicon | COLOURS | {"one"}:
            words.append(self.peek())
            self.i += 1
        if not words:
            if self.i > start and self.peek() not in ("", ",", "."):
                raise self.fail(f"the scene has no object called {self.peek()!r} "
                                f"(objects: {', '.join(th.name for th in self.scene.things)})")
            self.i = start
            if required:
                raise self.fail("an object of the scene is expected here")
            return []
        said = [w for w in words if w != "one"]
        found = [th.name for th in self.scene.things if set(said) <= th.words]
        phrase = " ".join(self.t[start:self.i])
        if not said or not found:
            raise NotUnderstood(f"not understood: {phrase!r}: no object of the scene matches "
                                f"(objects: {', '.join(th.name for th in self.scene.things)})")
        if len(found) > 1:
            raise NotUnderstood(f"not understood: {phrase!r} is ambiguous: it could be {' or '.join(found)}")
        names = self._mention(found)
        if coordinate and self.peek() == "and" and self.object_ahead_at(1) and self.peek(1) not in ("it", "them"):
            self.i += 1
            return names + self.noun_phrase(required=True, coordinate=True)
        return names

    def _mention(self, names: list[str]) -> list[str]:
        self.mentions += names
        self.current += names
        return names

    def _it(self, reflexive: list[str] | None) -> str:
        if reflexive:
            return reflexive[0]
        for name in reversed(self.mentions):
            if name not in self.current:
                return name
        raise self.fail("'it' refers to no object named before")

    def _them(self, word: str) -> list[str]:
        named = list(dict.fromkeys(self.mentions))
        if word == "both" and len(named) != 2:
            raise self.fail(f"'both' needs exactly two objects named before ({len(named)} were)")
        if len(named) < 2:
            raise self.fail("'them' needs two or more objects named before")
        return named
