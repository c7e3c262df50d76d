"""Steps of the instruction + the perceived scene -> a plan of cost primitives (docs/coral-language.md).

A primitive is a general piece with geometric parameters: approach a face, push to a fixture / a marker / the
table edge / along a direction by a distance, press with a force for a time, grasp across the side that fits
(or an overhanging end), lift, carry to a marker, place on it, rotate about a bottom edge or over a fixture,
withdraw, hold still. Consecutive primitives form a segment that one cost builder writes (its stages share
their terms); `kintsugi.methods.coral.costlib` writes the code. What the geometry cannot do (a top grasp on an
object wider than the open gripper, a flat object turned over with no fixture, a force beyond the robot's
limit) is refused here with the reason, as is anything the instruction forbids and also asks for.
"""

from __future__ import annotations

import math

from kintsugi.methods.coral.language import Reader, Step
from kintsugi.methods.coral.primitives import (AXES, DEFAULT_HOLD_S, DEFAULT_PRESS_S, DEFAULT_PUSH_M, MAX_PUSH_M,
                                               MIN_OVERHANG_LENGTH_M, ROUND_SHAPES, CostPlan, Primitive, Segment,
                                               _axis, _centre, _dirname, around, fits, tall)
from kintsugi.methods.coral.nouns import NotUnderstood
from kintsugi.methods.coral.types import FormulationRequest, ObjectState


class Planner:
    def __init__(self, req: FormulationRequest) -> None:
        self.req = req
        self.objects = {o.name: o for o in req.objects}
        self.fixtures = {f.name: f for f in req.fixtures}
        self.notes: list[str] = []
        self.segments: list[Segment] = []
        self.held: str | None = None
        self.over_edge: set[str] = set()
        self.pushed_to: dict[str, str] = {}
        self.moved: set[str] = set()
        """Objects a primitive other than a slide has moved (a later distance has no known origin)."""
        self.where: dict[str, tuple] = {}
        """Where a slide left an object (the next leg starts there)."""
        self.avoid: set[str] = set()
        """Fixtures the instruction forbids touching: pushes go round them."""

    def obj(self, s: Step) -> ObjectState:
        if s.obj is None or s.obj not in self.objects:
            raise NotUnderstood(f"not understood: {s.words!r}: one object per step (the scene holds "
                                f"{', '.join(self.objects)})")
        return self.objects[s.obj]

    def add(self, builder: str, o: ObjectState | None, prims: list[Primitive], **args: object) -> None:
        self.segments.append(Segment(builder, o.name if o else None, prims, dict(args)))
        if o is not None and builder not in ("slide", "hold"):
            self.moved.add(o.name)

    # --- verbs ----------------------------------------------------------------------------------------------
    def pick(self, s: Step) -> None:
        o = self.obj(s)
        if o.name in self.over_edge and self.segments and self.segments[-1].builder == "push_over_edge":
            self.add("pick_overhang", o, [Primitive("approach", o.name, {"at": "under-overhang"}),
                                          Primitive("grasp", o.name, {"at": "overhang"}),
                                          Primitive("lift", o.name), Primitive("hold", None, {"s": 0.5})])
            self.held = o.name
            return
        if s.part is not None:
            raise NotUnderstood(f"not understood: {s.words!r}: a grasp by its {s.part} is taken where the {s.part} "
                                "sticks out over the table edge: push it there first ('push the ... until its "
                                f"{s.part} sticks out over the table edge, then pick it up')")
        if not fits(o, self.req.robot.max_opening_m):
            w = min(o.size_m[0], o.size_m[1])
            raise NotUnderstood(f"not understood: {s.words!r}: {o.label} is {w * 100:.0f} cm across its narrower "
                                f"side, too wide for the {self.req.robot.max_opening_m * 100:.0f} cm gripper from "
                                "above; slide it until it sticks out over the table edge first")
        self.add("pick", o, [Primitive("grasp", o.name, {"across": "side-that-fits"}), Primitive("lift", o.name)])
        self.held = o.name
        if s.relation == "onto" and s.target is not None and s.target.kind == "marker":
            self._place(o, s)

    def place(self, s: Step) -> None:
        o = self.obj(s)
        if s.relation != "onto" or s.target is None or s.target.kind != "marker":
            where = ", ".join(m.name for m in self.req.markers) or "none in this scene"
            raise NotUnderstood(f"not understood: {s.words!r}: put it where? on a marker the scene holds ({where})")
        if self.held != o.name:
            self.add("pick", o, [Primitive("grasp", o.name, {"across": "side-that-fits"}),
                                 Primitive("lift", o.name)])
        self._place(o, s)

    def _place(self, o: ObjectState, s: Step) -> None:
        m = s.target.name  # type: ignore[union-attr]
        self.segments = [g for g in self.segments if not (g.builder == "hold" and g.obj == o.name)]
        self.add("place", o, [Primitive("carry", o.name, {"to": m}), Primitive("place", o.name, {"on": m}),
                              Primitive("release", o.name), Primitive("withdraw", None, {"dz": "up"})], marker=m)
        self.held = None

    def push(self, s: Step) -> None:
        o = self.obj(s)
        if s.said.startswith("roll") and (o.shape or "box") not in ROUND_SHAPES:
            raise NotUnderstood(f"not understood: {s.words!r}: {o.label} is a {o.shape or 'box'}; only a round "
                                "object rolls (push or slide it)")
        t = s.target
        if s.relation in ("against", "toward") and t is not None and t.kind == "fixture":
            self._push_to(o, t.name)
        elif s.relation in ("onto", "toward") and t is not None and t.kind == "marker":
            self._slide(o, s, marker=t.name)
        elif s.relation == "over-edge":
            if s.distance_m is not None or s.direction is not None:
                raise NotUnderstood(f"not understood: {s.words!r}: over the edge goes forward until it overhangs; "
                                    "give no other direction or distance")
            axis, sign = 0, 1.0
            yaw = math.radians(o.yaw_deg)
            length = abs(o.size_m[0] * math.cos(yaw)) + abs(o.size_m[1] * math.sin(yaw))
            if length < MIN_OVERHANG_LENGTH_M:
                raise NotUnderstood(f"not understood: {s.words!r}: {o.label} is {length * 100:.0f} cm long: it would "
                                    f"fall off before it sticks out far enough to be pinched (it takes "
                                    f"{MIN_OVERHANG_LENGTH_M * 100:g} cm)")
            self.add("push_over_edge", o, [Primitive("approach", o.name, {"face": _dirname(axis, -sign)}),
                                           Primitive("push", o.name, {"to": "edge"}),
                                           Primitive("withdraw", None, {"dz": "up"})])
            self.over_edge.add(o.name)
        elif s.relation == "away" and t is not None:
            if t.kind == "fixture":
                fx, fy = _centre(self.fixtures[t.name])
            elif t.kind == "object" and t.name in self.objects:
                fx, fy = self.objects[t.name].pos_m[:2]
            else:
                raise NotUnderstood(f"not understood: {s.words!r}: away from what?")
            axis, sign = _axis(o.pos_m[0] - fx, o.pos_m[1] - fy)
            self._slide(o, s, axis=axis, sign=sign)
        elif s.direction is not None:
            if s.direction not in AXES:
                raise NotUnderstood(f"not understood: {s.words!r}: push {s.direction}?")
            self._slide(o, s, axis=AXES[s.direction][0], sign=AXES[s.direction][1])
        elif s.relation == "toward" and t is not None and t.kind == "object":
            ox, oy = self.objects[t.name].pos_m[:2]
            axis, sign = _axis(ox - o.pos_m[0], oy - o.pos_m[1])
            self._slide(o, s, axis=axis, sign=sign)
        else:
            raise NotUnderstood(f"not understood: {s.words!r}: push it where? (against a fixture, onto a marker, "
                                "over the table edge, away from something, or left/right/forward/back by a distance)")
        if s.force_n is not None:
            self.press(s)

    def _push_to(self, o: ObjectState, fixture: str) -> None:
        fx, fy = _centre(self.fixtures[fixture])
        axis, sign = _axis(fx - o.pos_m[0], fy - o.pos_m[1])
        self.add("push_to_fixture", o, [Primitive("approach", o.name, {"face": _dirname(axis, -sign)}),
                                        Primitive("push", o.name, {"to": fixture, "dir": _dirname(axis, sign)})],
                 fixture=fixture, axis=axis, sign=sign)
        self.pushed_to[o.name] = fixture

    def _slide(self, o: ObjectState, s: Step, marker: str | None = None, axis: int = 0, sign: float = 1.0) -> None:
        origin = self.where.get(o.name, ("first", 0.0, 0.0))
        if marker is not None:
            if s.distance_m is not None or s.direction is not None:
                raise NotUnderstood(f"not understood: {s.words!r}: onto the marker says where it stops; give no "
                                    "other direction or distance")
            goal: tuple = ("marker", marker)
            face = "behind"
        else:
            d = s.distance_m
            if d is None:
                d = DEFAULT_PUSH_M
                self.notes.append(f"{s.words!r} names no distance: {DEFAULT_PUSH_M * 100:g} cm")
            if not 0.005 <= d <= MAX_PUSH_M:
                raise NotUnderstood(f"not understood: {s.words!r}: a push of {d * 100:g} cm (the language pushes "
                                    f"0.5 to {MAX_PUSH_M * 100:g} cm)")
            if origin[0] != "first" or o.name in self.moved:
                raise NotUnderstood(f"not understood: {s.words!r}: a push by a distance measures from where the object "
                                    "starts; after another move of it, give a target instead (a fixture or a marker)")
            step = [0.0, 0.0]
            step[axis] = sign * d
            goal = ("first", round(origin[1] + step[0], 4), round(origin[2] + step[1], 4))
            face = _dirname(axis, -sign)
        legs = around(o, origin, goal, self.req, self.avoid, self.notes)
        for i, (a, b) in enumerate(legs):
            to = {"marker": lambda: {"to": b[1]}, "first": lambda: {"dir": _dirname(axis, sign), "m": round(d, 4)},
                  "point": lambda: {"via": f"{b[1]:.3f},{b[2]:.3f}"}}[b[0]]()
            self.add("slide", o, [Primitive("approach", o.name, {"face": face if i == 0 else "behind"}),
                                  Primitive("push", o.name, {**to, **({"avoid": ",".join(sorted(self.avoid))}
                                                                      if self.avoid else {})}),
                                  *([Primitive("withdraw", None)] if b[0] != "point" else [])],
                     origin=a, goal=b, avoid=sorted(self.avoid), tol=0.02 if b[0] == "point" else None)
        self.where[o.name] = goal

    def press(self, s: Step) -> None:
        o = self.obj(s)
        fixture = s.target.name if s.target is not None and s.target.kind == "fixture" else \
            self.pushed_to.get(o.name)
        if fixture is None:
            if len(self.fixtures) != 1:
                raise NotUnderstood(f"not understood: {s.words!r}: press it against what? (a fixture: "
                                    f"{', '.join(self.fixtures) or 'none in this scene'})")
            fixture = next(iter(self.fixtures))
        if s.force_n is None:
            raise NotUnderstood(f"not understood: {s.words!r}: with what force? (e.g. 'with a force of 5 N')")
        limit = self.req.robot.force_limit_n
        if not 0 < s.force_n <= limit:
            raise NotUnderstood(f"not understood: {s.words!r}: {s.force_n:g} N is outside what the robot can "
                                f"press (0 to {limit:g} N)")
        if self.pushed_to.get(o.name) != fixture:
            self._push_to(o, fixture)
        dur = s.duration_s
        if dur is None:
            dur = DEFAULT_PRESS_S
            self.notes.append(f"{s.words!r} names no duration: {DEFAULT_PRESS_S:g} s")
        seg = self.segments[-1]
        self.add("press", o, [Primitive("press", o.name, {"against": fixture, "n": s.force_n, "s": dur})],
                 fixture=fixture, axis=seg.args["axis"], sign=seg.args["sign"], force=s.force_n, duration=dur)

    def flip(self, s: Step) -> None:
        o = self.obj(s)
        fixture = s.using or (s.target.name if s.target is not None and s.target.kind == "fixture" else None)
        if tall(o):
            if s.orient == "end":
                raise NotUnderstood(f"not understood: {s.words!r}: {o.label} already stands on its end")
            axis, sign = self._tip_direction(o, s, fixture)
            self.add("tip", o, [Primitive("approach", o.name, {"face": _dirname(axis, -sign), "at": "high"}),
                                Primitive("rotate", o.name, {"about": "bottom-edge", "dir": _dirname(axis, sign)}),
                                Primitive("withdraw", None), Primitive("hold", None, {"until": "still"})],
                     axis=axis, sign=sign)
            return
        if fixture is None:
            have = ", ".join(self.fixtures)
            raise NotUnderstood(f"not understood: {s.words!r}: {o.label} lies flat; turning it over takes a fixture "
                                "to pivot it against" + (f": say which ('using the {have.split(',')[0]}')" if have
                                                         else ", and the scene has none"))
        if s.direction is not None or s.distance_m is not None:
            raise NotUnderstood(f"not understood: {s.words!r}: a pivot goes toward its fixture; give no direction")
        fx, fy = _centre(self.fixtures[fixture])
        axis, sign = _axis(fx - o.pos_m[0], fy - o.pos_m[1])
        self.add("pivot", o, [Primitive("approach", o.name, {"face": _dirname(axis, -sign)}),
                              Primitive("push", o.name, {"to": fixture, "dir": _dirname(axis, sign)}),
                              Primitive("approach", o.name, {"face": _dirname(axis, -sign), "at": "high"}),
                              Primitive("rotate", o.name, {"about": fixture}),
                              Primitive("withdraw", None), Primitive("hold", None, {"until": "still"})],
                 fixture=fixture, axis=axis, sign=sign)

    def _tip_direction(self, o: ObjectState, s: Step, fixture: str | None) -> tuple[int, float]:
        if s.direction is not None:
            return AXES[s.direction]
        t = s.target
        if fixture is not None or (t is not None and t.kind == "fixture"):
            fx, fy = _centre(self.fixtures[fixture or t.name])  # type: ignore[union-attr]
            away = s.relation == "away"
            axis, sign = _axis(fx - o.pos_m[0], fy - o.pos_m[1])
            return axis, -sign if away else sign
        if s.relation in ("away", "toward") and t is not None and t.kind == "object":
            ox, oy = self.objects[t.name].pos_m[:2]
            axis, sign = _axis(ox - o.pos_m[0], oy - o.pos_m[1])
            return axis, -sign if s.relation == "away" else sign
        if self.fixtures:  # toward the nearest fixture: it stops a slide
            f = min(self.fixtures.values(), key=lambda f: math.dist(_centre(f), o.pos_m[:2]))
            return _axis(_centre(f)[0] - o.pos_m[0], _centre(f)[1] - o.pos_m[1])
        home = self.req.robot.home_m
        return _axis(o.pos_m[0] - home[0], o.pos_m[1] - home[1])

    def hold(self, s: Step) -> None:
        d = s.duration_s
        if d is None:
            d = DEFAULT_HOLD_S
            self.notes.append(f"{s.words!r} names no duration: {DEFAULT_HOLD_S:g} s")
        self.add("hold", None, [Primitive("hold", None, {"s": d})], seconds=d)


ALLOWED = {
    "pick": {"part", "relation", "target"}, "place": {"relation", "target"},
    "push": {"relation", "target", "direction", "distance_m", "force_n", "duration_s", "part"},
    "press": {"relation", "target", "force_n", "duration_s"},
    "flip": {"orient", "using", "direction", "relation", "target"}, "hold": {"duration_s"}, "touch": set(),
}
"""What each verb may be told; anything else in its clause is refused, never dropped."""
MODIFIER_WORDS = {"part": "part", "relation": "target", "target": "target", "direction": "direction",
                  "distance_m": "distance", "force_n": "force", "duration_s": "duration",
                  "orient": "orientation", "using": "fixture to use"}


def check_modifiers(s: Step) -> None:
    if s.negated:
        return
    given = {k for k in MODIFIER_WORDS if getattr(s, k) is not None}
    extra = given - ALLOWED[s.verb]
    if s.verb == "push" and s.duration_s is not None and s.force_n is None:
        extra.add("duration_s")
    if s.verb == "push" and s.part is not None and s.relation != "over-edge":
        extra.add("part")
    if extra:
        what = ", ".join(sorted({MODIFIER_WORDS[k] for k in extra}))
        raise NotUnderstood(f"not understood: {s.words!r}: '{s.verb}' takes no {what} here "
                            "(a duration goes with a press or a hold, a distance or direction with a push)")


VERB_OF = {"grasp": "pick", "lift": "pick", "carry": "place", "place": "place", "release": "place", "push": "push",
           "press": "press", "rotate": "flip"}


def plan_instruction(req: FormulationRequest) -> CostPlan:
    """The instruction and the scene -> the primitives to compose, or NotUnderstood with the reason."""
    reader = Reader(req)
    steps = reader.read(req.task)
    positive = [s for s in steps if not s.negated]
    negated = [s for s in steps if s.negated]
    if not positive:
        raise NotUnderstood("not understood: nothing to do: the instruction only says what not to do ("
                            + "; ".join(s.words for s in negated) + "); say what to do")
    p = Planner(req)
    p.avoid = {s.obj for s in negated if s.obj in p.fixtures}
    for s in positive:
        if s.verb == "touch":
            raise NotUnderstood(f"not understood: {s.words!r}: 'touch' is only understood forbidden "
                                "('don't touch the cubes')")
        check_modifiers(s)
        if p.held is not None and s.obj == p.held and s.verb in ("push", "press", "flip", "pick"):
            raise NotUnderstood(f"not understood: {s.words!r}: {s.obj} is in the hand then; put it on a marker first")
        getattr(p, s.verb)(s)
    if not any(g.builder != "hold" for g in p.segments):
        raise NotUnderstood("not understood: nothing to do: the instruction moves no object")
    if p.segments[-1].builder == "pick":
        p.add("hold", None, [Primitive("hold", None, {"s": 0.5})], seconds=0.5)
    for s in negated:
        if s.obj in p.fixtures:
            if s.verb != "touch":
                raise NotUnderstood(f"not understood: {s.words!r}: a fixture does not move; say 'without touching'")
            p.notes.append(f"forbidden: {s.words}; the hand and the object keep clear of {s.obj}")
            continue
        banned = set((s.obj or "").split(","))
        for g in p.segments:
            for prim in g.prims:
                if prim.obj in banned and (s.verb == "touch" or VERB_OF.get(prim.name) == s.verb
                                           or (s.verb == "place" and VERB_OF.get(prim.name) in ("pick", "push"))):
                    raise NotUnderstood(f"not understood: the instruction both forbids {s.words!r} and asks for it "
                                        f"({prim})")
        p.notes.append(f"forbidden, and not in the plan: {s.words}")
    return CostPlan(steps=steps, segments=p.segments, notes=reader.lex.notes + p.notes)


__all__ = ["CostPlan", "Primitive", "Segment", "plan_instruction"]
