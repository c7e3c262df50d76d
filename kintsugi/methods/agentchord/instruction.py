"""What the instruction says beyond its goal: which arm takes which object, what is held up, and so which
grounded operators a plan may use."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from kintsugi.methods.agentchord.language import Scene
from kintsugi.methods.agentchord.reading import Reading, read
from kintsugi.methods.agentchord.symbolic import ground


def scene_of(objects: Any, arms: list[str], regions: Any = (), domain: Any = None, first: Any = ()) -> Scene:
    """The scene as the language names it: objects by name words, and by kind and colour where perception
    reports them; `stands` from perception's uprightness (in the first observation when re-planning)."""
    seen = {getattr(o, "name", o): o for o in objects}
    standing = {getattr(o, "name", ""): o for o in first} or seen
    stands = {n: bool(getattr(o, "upright", None)) for n, o in standing.items() if not isinstance(o, str)}
    return Scene.of(list(seen), arms=arms, regions=tuple(regions),
                    directions=tuple(domain.directions) if domain is not None else None,
                    kinds={n: getattr(o, "kind", None) or "" for n, o in seen.items() if not isinstance(o, str)},
                    colours={n: getattr(o, "colour", None) for n, o in seen.items() if not isinstance(o, str)},
                    stands=stands)


@lru_cache(maxsize=256)
def reading_of(task: str, scene: Scene, predicates: frozenset[str] | None = None) -> Reading:
    """The instruction read in the controlled language (NotUnderstood when it is outside it)."""
    return read(task, scene, predicates)


def arms_named(task: str, arms: list[str], objects: Any = ()) -> list[str]:
    """The arms an instruction uses ("using the right arm"); all arms when it names none."""
    return reading_of(task, scene_of(objects, arms)).arms


def arm_bindings(task: str, arms: list[str], objects: Any) -> dict[str, str]:
    """Objects the instruction gives to one arm ("the cup with the left arm", "use the right arm for the
    spoon", "the blue block with the left hand") -> that arm (the giver, for an object handed over)."""
    return reading_of(task, scene_of(objects, arms)).bindings


def held_up(task: str, objects: Any, arms: list[str] = ("left", "right")) -> list[str]:
    """Objects the instruction holds up while a later step acts on them ("hold the cup up, pour into it")."""
    return reading_of(task, scene_of(objects, list(arms))).held_up


def instructed_ops(task: str, domain: Any, arms: list[str], objects: list[str], places: list[str] = (),
                   reading: Reading | None = None) -> list:
    """The grounded operators the instruction allows: an object given to one arm is taken from the table by
    that arm only (no instance that picks it up adds holding(other arm, it); a handover may pass it on), unless
    it lies where that arm cannot reach it (a knocked or dropped object: the other arm takes it up, and a
    handover gives it back where the task needs the instruction's arm), or until
    it has handed the object over to the other arm: from then on only the taker picks it up again after a
    drop (the giver may not reach where it fell); an object to be held up must be lifted before any operator makes a fact that
    names it as the target (carry over it, pour into it); an object given to both arms is taken by both at once.
    """
    from dataclasses import replace

    if reading is None:
        reading = reading_of(task, scene_of(objects, list(arms)))
    bound, up = {o: a for o, a in reading.bindings.items() if a in arms}, reading.held_up
    handovers = any(p.name == "handed_over" and len(p.params) == 3 for p in domain.predicates)
    reaches = any(p.name == "reaches" and len(p.params) == 2 for p in domain.predicates)
    both = set(reading.both_arms)
    out = []
    for op in ground(domain, arms, objects, places):
        if both and _one_arm_take(op, both):
            continue
        other = _other_taker(op, bound) or _other_hand(op, bound)
        if other is not None and not handovers:
            continue
        variants = [op]
        if other is not None:
            arm, obj = other
            variants = [replace(op, pre_pos=op.pre_pos | {("handed_over", obj, bound[obj], arm)})]
            if reaches:  # where the instruction's arm cannot reach it, the arm that can takes it up
                variants.append(replace(op, pre_neg=op.pre_neg | {("reaches", bound[obj], obj)}))
        elif handovers and (own := _own_take(op, bound)) is not None:  # once handed over, the taker's object
            arm, obj = own
            variants = [replace(op, pre_neg=op.pre_neg | {("handed_over", obj, arm, b) for b in arms if b != arm})]
        for op in variants:
            targets = {a[2] for a in op.add if len(a) == 3 and a[1] in objects and a[2] in up}
            if targets:
                op = replace(op, pre_pos=op.pre_pos | {("lifted", t) for t in targets})
            out.append(op)
    return out


def _one_arm_take(op: Any, both: set[str]) -> bool:
    """The operator takes from the table, with one arm alone, an object the instruction gives to both arms."""
    takers: dict[str, int] = {}
    for a in op.add:
        if a[0] == "holding" and a[2] in both and ("released", a[2]) in op.pre_pos:
            takers[a[2]] = takers.get(a[2], 0) + 1
    return any(n == 1 for n in takers.values())


def _other_taker(op: Any, bound: dict[str, str]) -> tuple[str, str] | None:
    """(arm, object) when the operator alone takes from the table an object the instruction gives to another
    arm (a two-arm take is not the other arm taking it alone)."""
    takers: dict[str, int] = {}
    for a in op.add:
        if a[0] == "holding":
            takers[a[2]] = takers.get(a[2], 0) + 1
    for a in op.add:
        if (a[0] == "holding" and a[2] in bound and bound[a[2]] != a[1] and ("released", a[2]) in op.pre_pos
                and takers[a[2]] == 1):
            return a[1], a[2]
    return None


def _own_take(op: Any, bound: dict[str, str]) -> tuple[str, str] | None:
    """(arm, object) for a one-arm operator by the arm the instruction gives the object to, on it lying free."""
    b = dict(op.binding)
    arm, obj = b.get("?arm"), b.get("?obj")
    if (arm is not None and bound.get(obj) == arm and ("released", obj) in op.pre_pos
            and sum(1 for v in op.spec.params.values() if v == "arm") == 1):
        return arm, obj
    return None


def _other_hand(op: Any, bound: dict[str, str]) -> tuple[str, str] | None:
    """(arm, object) for a one-arm operator that handles an object lying free (`released` before it) which the
    instruction gives to the other arm (standing a fallen bottle up is the bottle's arm's job, as taking it is)."""
    b = dict(op.binding)
    arm, obj = b.get("?arm"), b.get("?obj")
    if (arm is not None and obj in bound and bound[obj] != arm and ("released", obj) in op.pre_pos
            and sum(1 for v in op.spec.params.values() if v == "arm") == 1):
        return arm, obj
    return None
