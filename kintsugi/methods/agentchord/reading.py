"""What an instruction in the controlled language means: clauses -> the formal goal, the arms it allows, which
arm takes which object, and which objects are held up while others act on them.

Steps run in the order written; the goal is where things end: each object's last placement (one per object),
its orientation, whether it is released, and the history facts (poured, handed over, not dropped, not moved).
A placement on the table or in a region of it that states no orientation leaves the object the way it rests:
upright if it was seen standing, flat otherwise; an object something is put on or into keeps resting so, and
one poured into stays upright.
Contradictions (placed twice, moved and not moved, upright and flat) are refused, never resolved silently.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from kintsugi.methods.agentchord.grammar import parse
from kintsugi.methods.agentchord.language import Clause, Group, NotUnderstood, Scene

PLACES = {"table": "on_table", "on": "on", "into": "inside", "beside": "beside", "left_of": "left_of",
          "right_of": "right_of"}
SIDE_SPOTS = {"left_of": "beside_left", "right_of": "beside_right"}
"""`X to the left of Y, along Y's side`: the spot alongside Y's side, a region relative to Y."""


@dataclass
class Reading:
    goal: list[str]
    arms: list[str]
    """The arms the instruction uses (all when it names none)."""
    bindings: dict[str, str] = field(default_factory=dict)
    """Object -> the one arm the instruction gives it to first (the giver, when it is handed over)."""
    both_arms: list[str] = field(default_factory=list)
    """Objects the instruction gives to both arms at once."""
    held_up: list[str] = field(default_factory=list)
    """Objects held up while a later step acts on them (pour into it, put something on it)."""


@dataclass
class _Object:
    place: tuple | None = None
    placed_by: str = ""
    orient: str | None = None
    orient_by: str = ""
    released: bool | None = None
    heading: str | None = None
    held: bool = False
    holder: str | None = None


class _Meaning:
    def __init__(self, scene: Scene, predicates: frozenset[str] | None) -> None:
        self.scene, self.predicates = scene, predicates
        self.objects: dict[str, _Object] = {}
        self.history: list[str] = []
        self.arms: set[str] = set()
        self.bindings: dict[str, str] = {}
        self.both: list[str] = []
        self.up: list[str] = []
        self.keep_upright: list[str] = []
        self.not_moved: list[str] = []
        self.supports: list[str] = []
        """Objects something is put on or into: they keep resting the way they rest (a tipped bin spills)."""

    def of(self, name: str) -> _Object:
        return self.objects.setdefault(name, _Object())

    def run(self, clauses: list[Clause]) -> Reading:
        for c in clauses:
            if c.negated is not None:
                what, objs = c.negated
                for o in objs:
                    self.negate(what, o, c)
            for arms, obj in c.uses:
                self.arms |= set(arms)
                if obj is not None:
                    self.bind(obj, arms, c)
            for g in c.groups:
                self.unused(g, c)
                getattr(self, "do_" + c.verb)(g, c)
                for what, o in g.without:
                    self.negate(what, o, c)
        return self.reading()

    # --- steps ------------------------------------------------------------------------------------
    def bind(self, obj: str, arms: tuple[str, ...], c: Clause) -> None:
        self.arms |= set(arms)
        if len(arms) == 2:
            if obj in self.bindings:
                raise NotUnderstood(f"not understood: {c.words!r}: {obj} is given to the {self.bindings[obj]} "
                                    "arm and to both arms")
            if obj not in self.both:
                self.both.append(obj)
            return
        arm = arms[0]
        st = self.of(obj)
        if obj in self.both:
            raise NotUnderstood(f"not understood: {c.words!r}: {obj} is given to both arms and to the {arm} arm")
        if obj in self.bindings and self.bindings[obj] != arm and st.holder != arm:
            raise NotUnderstood(f"not understood: {c.words!r}: {obj} is given to the {self.bindings[obj]} arm, "
                                f"then to the {arm} arm with no hand-over between")
        self.bindings.setdefault(obj, arm)
        st.holder = st.holder or arm

    def unused(self, g: Group, c: Clause) -> None:
        """A phrase the step's verb does nothing with is refused, never dropped."""
        allowed = {"take": {"arms", "rims", "up"}, "place": {"arms", "place", "orient", "heading", "side_of", "down",
                                                             "back", "rims", "stack", "up"},
                   "pour": {"arms", "source", "place"}, "handover": {"arms", "to_arm", "over"},
                   "release": {"arms"}, "fold": {"half"}}[c.verb]
        said = {k for k in ("place", "orient", "heading", "side_of", "source", "to_arm") if getattr(g, k) is not None}
        said |= {"arms"} if g.arms else set()
        said |= {"rims"} if g.rims else set()
        said |= g.particles
        extra = sorted(said - allowed)
        if extra:
            raise NotUnderstood(f"not understood: {c.words!r}: '{c.words.split()[0]}' does nothing with its "
                                f"{', '.join(extra)} phrase")

    def do_take(self, g: Group, c: Clause) -> None:
        if g.place is not None or g.orient is not None:
            raise NotUnderstood(f"not understood: {c.words!r}: taking an object says where it goes with 'put'")
        if c.words.split()[0] == "keep" and "up" not in g.particles:
            raise NotUnderstood(f"not understood: {c.words!r}: 'keep' takes up, raised, upright, or where it is")
        for o in g.objects:
            st = self.of(o)
            st.held, st.released = True, False
            if g.arms:
                self.bind(o, g.arms, c)

    def do_place(self, g: Group, c: Clause) -> None:
        place = g.place
        if "stack" in g.particles and (place is None or place[0] != "on"):
            raise NotUnderstood(f"not understood: {c.words!r}: 'stack' puts an object on another: 'stack X on Y'")
        if place is None and (g.particles & {"down", "back"} or g.orient is not None):
            place = ("table",)
        if place is None:
            raise NotUnderstood(f"not understood: {c.words!r}: where should it go? (on the table, on/into/beside "
                                "an object, to the left/right of one, in a region)")
        if g.side_of is not None:
            if place[0] not in SIDE_SPOTS or place[1] != g.side_of:
                raise NotUnderstood(f"not understood: {c.words!r}: 'along {g.side_of}'s side' goes with "
                                    f"'to the left/right of {g.side_of}'")
            place = ("region", f"{SIDE_SPOTS[place[0]]}({g.side_of})")
        for o in g.objects:
            if len(place) > 1 and place[1] == o:
                raise NotUnderstood(f"not understood: {c.words!r}: {o} cannot go {place[0]} itself")
            st = self.of(o)
            if st.place is not None and st.place != place:
                raise NotUnderstood(f"not understood: {c.words!r}: {o} is placed twice ({st.placed_by!r}, then "
                                    f"{c.words!r}); the language states where each object ends, once")
            st.place, st.placed_by, st.released, st.held = place, c.words, True, False
            if g.orient is not None:
                self.orient(o, g.orient, c)
            if g.heading is not None:
                st.heading = g.heading
            if g.arms:
                self.bind(o, g.arms, c)
            if len(place) > 1 and place[0] != "region":
                self.target(place[1])
            if place[0] in ("on", "into"):
                self.supports.append(place[1])

    def do_pour(self, g: Group, c: Clause) -> None:
        src = g.source or (g.objects[0] if g.objects else None)
        if src is None or g.place is None or g.place[0] != "into":
            raise NotUnderstood(f"not understood: {c.words!r}: pour from an object into another: "
                                "'pour water from the bottle into the cup'")
        dst = g.place[1]
        if dst == src:
            raise NotUnderstood(f"not understood: {c.words!r}: {src} cannot pour into itself")
        self.history.append(f"poured({src}, {dst})")
        self.orient(dst, "upright", c, implied=True)
        self.target(dst)
        if g.arms:
            self.bind(src, g.arms, c)

    def do_handover(self, g: Group, c: Clause) -> None:
        if g.to_arm is None:
            raise NotUnderstood(f"not understood: {c.words!r}: hand it over to which arm? ('to the right arm')")
        for o in g.objects:
            st = self.of(o)
            giver = st.holder or next((a for a in self.scene.arms if a != g.to_arm), None)
            if giver is None or giver == g.to_arm:
                raise NotUnderstood(f"not understood: {c.words!r}: the {g.to_arm} arm already has {o}")
            self.history.append(f"handed_over({o}, {giver}, {g.to_arm})")
            self.bindings.setdefault(o, giver)
            self.arms |= {giver, g.to_arm}
            st.holder, st.held, st.released = g.to_arm, True, False

    def do_release(self, g: Group, c: Clause) -> None:
        objs = g.objects or [o for o, st in self.objects.items() if st.held]
        if not objs:
            raise NotUnderstood(f"not understood: {c.words!r}: nothing is held to let go of")
        for o in objs:
            st = self.of(o)
            st.released, st.held = True, False

    def do_fold(self, g: Group, c: Clause) -> None:
        self.history += [f"folded({o})" for o in g.objects]

    def negate(self, what: str, o: str, c: Clause) -> None:
        if what == "moved":
            self.not_moved.append(o)
        elif what == "dropped":
            self.history.append(f"not dropped({o})")
        else:
            self.keep_upright.append(o)
            self.orient(o, "upright", c, implied=True)

    def orient(self, o: str, how: str, c: Clause, implied: bool = False) -> None:
        st = self.of(o)
        if st.orient is not None and st.orient != how:
            raise NotUnderstood(f"not understood: {c.words!r}: {o} would be both {st.orient} ({st.orient_by!r}) "
                                f"and {how}")
        st.orient, st.orient_by = how, c.words

    def target(self, y: str) -> None:
        """An object another acts on (poured into, put on): when held up then, it must be lifted first."""
        if self.of(y).held and y not in self.up:
            self.up.append(y)

    # --- the goal ---------------------------------------------------------------------------------
    def reading(self) -> Reading:
        goal: list[str] = []
        for o, st in self.objects.items():
            if o in self.not_moved and (st.place is not None or st.held):
                raise NotUnderstood(f"not understood: {o} is both moved ({st.placed_by or 'taken'!r}) and not to "
                                    "be moved")
            if st.place is not None:
                kind, *arg = st.place
                if kind == "region":
                    goal.append(f"in_region({o}, {arg[0]})")
                elif kind == "table":
                    goal.append(f"on_table({o})")
                else:
                    goal.append(f"{PLACES[kind]}({o}, {arg[0]})")
                resting = st.orient
                if resting is None and (kind in ("table", "region", "beside", "left_of", "right_of")
                                        or o in self.supports):
                    resting = self.resting(o)
                if resting is not None:
                    goal.append(f"{resting}({o})")
            elif st.orient is not None or o in self.supports:
                how = st.orient or self.resting(o)
                if how is not None:
                    goal.append(f"{how}({o})")
            if st.heading is not None:
                goal.append(f"heading({o}, {st.heading})")
            if st.held and st.place is None and not st.released:
                goal += self.held_up(o)
            elif st.released:
                goal.append(f"released({o})")
        goal += [h for h in self.history if h not in goal]
        goal += [f"not moved({o})" for o in dict.fromkeys(self.not_moved)]
        if not goal:
            raise NotUnderstood("not understood: no step of the instruction changes the scene (say what should "
                                "end where, e.g. 'put the cup on the plate')")
        if self.predicates is not None:
            self.check(goal)
        arms = [a for a in self.scene.arms if a in self.arms] or list(self.scene.arms)
        return Reading(goal=list(dict.fromkeys(goal)), arms=arms, bindings=dict(self.bindings),
                       both_arms=list(self.both), held_up=list(self.up))

    def resting(self, o: str) -> str | None:
        stands = next((th.stands for th in self.scene.things if th.name == o), None)
        return None if stands is None else ("upright" if stands else "flat")

    def held_up(self, o: str) -> list[str]:
        if self.predicates is None or "held_up" in self.predicates:
            return [f"held_up({o})"]
        return [f"lifted({o})", f"not released({o})"]

    def check(self, goal: list[str]) -> None:
        from kintsugi.methods.agentchord.types import parse_atom

        missing = []
        for g in goal:
            name = parse_atom(g)[1]
            if name not in self.predicates and name not in missing:
                missing.append(name)
        if missing:
            raise NotUnderstood("the instruction asks for " + ", ".join(g for g in goal if parse_atom(g)[1] in missing)
                                + f", and the action library has no predicate {' or '.join(map(repr, missing))} "
                                "(no operator makes it), so no plan can reach it")


def read(text: str, scene: Scene, predicates: frozenset[str] | None = None) -> Reading:
    """The instruction's meaning in the scene; `predicates`: the domain's predicate names (a goal needing one
    the domain lacks is refused, naming it). Raises NotUnderstood."""
    try:
        clauses = parse(text, scene)
    except NotUnderstood as exc:
        raise NotUnderstood(str(exc) + _needs(getattr(exc, "clauses", []), scene, predicates)) from None
    return _Meaning(scene, predicates).run(clauses)


def _needs(clauses: list[Clause], scene: Scene, predicates: frozenset[str] | None) -> str:
    """What the steps read before a refusal would need that the action library lacks ("; and ...")."""
    if not clauses or predicates is None:
        return ""
    try:
        _Meaning(scene, predicates).run(clauses)
    except NotUnderstood as exc:
        if "the action library has no predicate" in str(exc):
            return "; and " + str(exc)
    return ""
