"""The controlled language's grammar: a recursive-descent parser from an instruction's words to clauses.

instruction := step (boundary step)*            boundary := , ; : . then | and (before a verb)
step        := verb group ("and" group)* | "do not" neg-verb object | "use" arm "for" object ("and" ...)*
group       := (object | particle | orientation | place | arm | heading | manner | without)*
The full grammar, with examples, is docs/agentchord-language.md.
"""

from __future__ import annotations

from kintsugi.methods.agentchord.language import (CONNECTIVES, NEG_VERBS, SUBSTANCES, VERBS, Clause, Group,
                                                  NotUnderstood, Scene)
from kintsugi.methods.agentchord.nouns import Nouns


class Parser(Nouns):
    """Tokens -> clauses; `mentions` keeps the objects in the order they were named (for `it`, `them`, `both`)."""

    # --- instruction ----------------------------------------------------------------------------------
    def parse(self) -> list[Clause]:
        clauses: list[Clause] = self.clauses
        while self.i < len(self.t):
            tok = self.peek()
            if tok in ",.;:!" or tok in CONNECTIVES or self.eat("after", "that"):
                self.i += tok in ",.;:!" or tok in CONNECTIVES
                continue
            if tok == "(":
                raise self.fail("remarks in parentheses are not in the language")
            if tok in VERBS or tok in ("do", "never", "don"):
                clauses.append(self.clause())
            elif clauses and tok in ("each", "both") and self.peek(1) not in ("of", "back", "on", ""):
                self.i += 1
                start, end = self.i, self.i
                for g in clauses[-1].groups:
                    self.i = start
                    self.modifiers(g, clauses[-1].verb)
                    end = self.i
                self.i = end
            elif clauses and tok in ("without", "with", "using", "lying", "upright", "flat") and clauses[-1].groups:
                self.modifiers(clauses[-1].groups[-1], clauses[-1].verb)
            elif clauses and clauses[-1].verb not in ("use", "not") and self.object_ahead():
                clauses[-1].groups.append(self.group(clauses[-1].verb))
            else:
                raise self.fail(f"{tok!r} does not start a step; a step starts with one of: "
                                + ", ".join(sorted(set(VERBS) - {'keep', 'get'})))
        if not clauses:
            raise NotUnderstood("not understood: the instruction has no step (e.g. 'put the cup on the plate')")
        return clauses

    def clause(self) -> Clause:
        start = self.i
        if self.eat("do", "not") or self.eat("never") or self.eat("don", "t"):
            word = self.peek()
            if word not in NEG_VERBS:
                raise self.fail("after 'do not' the language knows: move, drop, tip (over), knock over")
            self.i += 1
            self.eat("over")
            objs = self.noun_phrase(required=True)
            self.eat("over")
            return Clause("not", " ".join(self.t[start:self.i]), negated=(NEG_VERBS[word], objs))
        verb = VERBS[self.peek()]
        word = self.peek()
        self.i += 1
        kept = self.kept(word, start)
        if kept is not None:
            return kept
        c = Clause(verb, word)
        if verb == "use":
            self.uses(c)
        else:
            if word == "stack":
                c.words = "stack"
            c.groups.append(self.group(verb, word))
            while self.peek() == "and" and self.peek(1) not in VERBS and self.peek(1) not in ("then", "do", "never"):
                self.i += 1
                c.groups.append(self.group(verb, word))
        c.words = " ".join(self.t[start:self.i])
        return c

    def kept(self, word: str, start: int) -> Clause | None:
        """`leave X where it is` / `leave X alone` (not moved) and `keep X upright` (not tipped)."""
        if word not in ("leave", "keep"):
            return None
        save = self.i
        objs = self.noun_phrase(coordinate=True)
        what = None
        if word == "leave" and (self.eat("where", "it", "is") or self.eat("where", "they", "are")
                                or self.eat("in", "place") or self.eat("alone") or self.eat("where", "it", "stands")):
            what = "moved"
        elif word == "keep" and (self.eat("upright") or self.eat("standing")):
            what = "tipped"
        if what is None or not objs:
            self.i, self.mentions = save, self.mentions[:len(self.mentions) - len(objs)]
            return None
        return Clause("not", " ".join(self.t[start:self.i]), negated=(what, objs))

    def uses(self, c: Clause) -> None:
        while True:
            arms = self.arm_phrase()
            if arms is None:
                raise self.fail("'use' takes an arm: 'use the left arm for the cup'")
            self.eat("only")
            obj = None
            if self.eat("for") or self.eat("to", "take") or self.eat("to", "carry"):
                objs = self.noun_phrase(required=True)
                for o in objs:
                    c.uses.append((arms, o))
                obj = objs
            if obj is None:
                c.uses.append((arms, None))
            if not (self.peek() == "and" and self.peek(1) in ("the", "left", "right", "both", "its")):
                return
            self.i += 1

    # --- one object phrase and what is said about it ----------------------------------------------
    def group(self, verb: str, word: str = "") -> Group:
        g = Group()
        self.current = []
        if word == "stack":
            g.particles.add("stack")
        if word == "stand":
            g.orient = "upright"
        self.modifiers(g, verb)
        if verb == "pour" and not g.objects and g.source:
            g.objects = [g.source]
        if g.objects:
            self.last_main = list(g.objects)
        if verb != "release" and not g.objects:
            raise self.fail(f"'{word or verb}' needs an object the scene has "
                            f"({', '.join(th.name for th in self.scene.things)})")
        return g

    def modifiers(self, g: Group, verb: str) -> None:
        while not self.at_boundary():
            if self.peek() == "and" and (self.peek(1) in VERBS or self.peek(1) in ("then", "do", "never")
                                         or self.object_ahead_at(1)):
                return
            if self.peek() == "and" and self.peek(1) in ("each", "both"):
                self.i += 1
                continue
            if not self.modifier(g, verb):
                raise self.fail("no phrase of the language starts here")

    def modifier(self, g: Group, verb: str) -> bool:  # noqa: C901 - one branch per phrase of the grammar
        p = self.peek()
        if p in ("up", "down", "back", "over", "half") or self.eat("in", "half"):
            if p in ("up", "down", "back", "over", "half"):
                self.i += 1
            g.particles.add(p if p != "in" else "half")
            return True
        if self.eat("raised") or self.eat("lifted") or self.eat("in", "the", "air"):
            g.particles.add("up")
            return True
        if self.eat("upright") or self.eat("standing", "up") or self.eat("standing") or self.eat("on", "its", "base"):
            return self._orient(g, "upright")
        if self.eat("lying", "flat") or self.eat("flat") or self.eat("lying", "down") or self.eat("level"):
            return self._orient(g, "flat")
        if p in ("upside", "sideways") or self.eat("on", "its", "side"):
            raise self.fail("the language knows two ways for an object to rest: upright and flat")
        if self.eat("along"):
            self.eat("the", "side", "of")
            objs = self.noun_phrase(required=True)
            if not (self.eat("'s", "side") or self.eat("'s", "sides") or self.eat("side")):
                self.eat("'s")
                if not self.eat("side"):
                    raise self.fail("'along' takes an object's side: 'along the plate's side'")
            g.side_of = objs[0]
            return True
        if p in ("with", "using"):
            save = self.i
            self.i += 1
            arms = self.arm_phrase()
            if arms is not None:
                self.eat("only")
                if g.arms and g.arms != arms:
                    raise self.fail("one phrase names two different arms")
                g.arms = arms
                return True
            self.i = save
            if self.eat("with", "its", "head") or self.eat("with", "the", "head"):
                self.eat("pointing") or self.eat("facing") or self.eat("pointed")
                return self._heading(g)
            return False
        if self.eat("pointing") or self.eat("facing") or self.eat("head", "pointing") or self.eat("head"):
            return self._heading(g)
        if self.eat("by"):
            self.eat("its") or self.eat("the")
            self.eat("side") or self.eat("two")
            if self.peek() in ("rims", "rim", "sides", "edges", "handles"):
                self.i += 1
                g.rims = True
                return True
            raise self.fail("'by' takes an object's rims or sides: 'by its side rims'")
        if self.eat("without"):
            word = self.peek()
            if word not in NEG_VERBS:
                raise self.fail("after 'without' the language knows: moving, dropping, tipping (over), knocking over")
            self.i += 1
            self.eat("over")
            objs = self.noun_phrase(reflexive=g.objects) if self.peek() not in (",", ".", "") else list(g.objects)
            self.eat("over")
            g.without += [(NEG_VERBS[word], o) for o in objs or g.objects]
            return True
        if verb == "pour" and self.eat("from") or verb == "pour" and self.eat("out", "of"):
            g.source = self.noun_phrase(required=True)[0]
            return True
        if verb == "handover" and self.eat("to"):
            arms = self.arm_phrase()
            if arms is None or len(arms) != 1:
                raise self.fail("a hand-over goes to one arm: 'hand it over to the right arm'")
            g.to_arm = arms[0]
            return True
        if verb == "pour" and p in SUBSTANCES or verb == "pour" and self.eat("the", "water"):
            self.i += p in SUBSTANCES
            self.eat("water")
            return True
        if self.place_phrase(g):
            return True
        if not g.objects and (self.object_ahead() or p in ("the", "a", "an")):
            g.objects = self.noun_phrase(required=True, coordinate=True, main=True)
            return True
        if p == "(":
            raise self.fail("remarks in parentheses are not in the language")
        if p == "its":
            raise self.fail("parts of an object ('its corners', 'its handle') are not in the language (the "
                            "action library grasps and places whole objects); name the object itself")
        return False

    def _orient(self, g: Group, how: str) -> bool:
        if g.orient not in (None, how):
            raise self.fail(f"the object cannot be both {g.orient} and {how}")
        g.orient = how
        return True

    def _heading(self, g: Group) -> bool:
        d = self.direction()
        if d is None:
            raise self.fail("a heading is one of: away from you, toward you, to the left, to the right")
        g.heading = d
        return True

    def place_phrase(self, g: Group) -> bool:
        start = self.i
        if self.eat("on", "the", "table") or self.eat("onto", "the", "table") or self.eat("on", "table"):
            return self._place(g, ("table",), start)
        for side in ("left", "right"):
            if (self.eat("to", "the", side, "of") or self.eat(side, "of") or self.eat("on", "the", side, "of")
                    or self.eat("at", "the", side, "of") or self.eat("to", side, "of")):
                return self._place(g, (f"{side}_of", self.noun_phrase(required=True)[0]), start)
        if self.eat("beside"):
            return self._place(g, ("beside", self.noun_phrase(required=True)[0]), start)
        if self.peek() in ("in", "into", "to", "at", "on") and self.region_ahead(1):
            self.i += 1
            return self._place(g, ("region", self.region()), start)
        if self.eat("into") or self.eat("in"):
            return self._place(g, ("into", self.noun_phrase(required=True)[0]), start)
        if self.eat("on"):
            return self._place(g, ("on", self.noun_phrase(required=True)[0]), start)
        return False

    def _place(self, g: Group, place: tuple, start: int) -> bool:
        if g.place is not None and g.place != place:
            self.i = start
            raise self.fail("one step puts an object in one place")
        g.place = place
        return True


def parse(text: str, scene: Scene) -> list[Clause]:
    """Raises NotUnderstood at the first words outside the language, with the steps read before them
    (`clauses`), so a refusal can also say what those steps would need."""
    p = Parser(text, scene)
    try:
        return p.parse()
    except NotUnderstood as exc:
        exc.clauses = p.clauses
        raise
