"""What the instruction says beyond its goal: which arm takes which object, what is held up, and so which
grounded operators a plan may use."""

from __future__ import annotations

import re
from typing import Any

from kintsugi.methods.agentchord.symbolic import ground

def arms_named(task: str, arms: list[str]) -> list[str]:
    """The arms an instruction asks for ("using the right arm"); all arms when it names none or both."""
    text = task.lower()
    named = [a for a in arms if re.search(rf"\b{a}\s+(arm|hand)\b", text)]
    return named or list(arms)


def arm_bindings(task: str, arms: list[str], objects: list[str]) -> dict[str, str]:
    """Objects the instruction gives to one arm ("the cup with the left arm", "the bottle with the right
    hand") -> that arm. "using the right arm" after a phrase names the arm for the whole task (`arms_named`),
    not for the object before it."""
    text = task.lower()
    out = {}
    for o in objects:
        for a in arms:
            if (re.search(rf"\b{re.escape(o.lower())}\s+with\s+(the\s+)?{a}\s+(arm|hand)\b", text)
                    or re.search(rf"\b{a}\s+(arm|hand)\s+for\s+(the\s+)?{re.escape(o.lower())}\b", text)):
                out[o] = a
    return out


def held_up(task: str, objects: list[str]) -> list[str]:
    """Objects the instruction asks to be held up while others act on them ("hold the cup up")."""
    text = task.lower()
    return [o for o in objects if re.search(rf"\bhold\s+(the\s+)?{re.escape(o.lower())}\s+up\b", text)]


def instructed_ops(task: str, domain: Any, arms: list[str], objects: list[str], places: list[str] = ()) -> list:
    """The grounded operators the instruction allows: an object given to one arm is taken from the table by
    that arm only (no instance that picks it up adds holding(other arm, it); a handover may pass it on), until
    it has handed the object over to the other arm: from then on only the taker picks it up again after a
    drop (the giver may not reach where it fell); an object to be held up must be lifted before any operator makes a fact that
    names it as the target (carry over it, pour into it)."""
    from dataclasses import replace

    bound, up = arm_bindings(task, arms, objects), held_up(task, objects)
    handovers = any(p.name == "handed_over" and len(p.params) == 3 for p in domain.predicates)
    out = []
    for op in ground(domain, arms, objects, places):
        other = _other_taker(op, bound) or _other_hand(op, bound)
        if other is not None and not handovers:
            continue
        if other is not None:
            arm, obj = other
            op = replace(op, pre_pos=op.pre_pos | {("handed_over", obj, bound[obj], arm)})
        elif handovers and (own := _own_take(op, bound)) is not None:  # once handed over, the taker's object
            arm, obj = own
            op = replace(op, pre_neg=op.pre_neg | {("handed_over", obj, arm, b) for b in arms if b != arm})
        targets = {a[2] for a in op.add if len(a) == 3 and a[1] in objects and a[2] in up}
        if targets:
            op = replace(op, pre_pos=op.pre_pos | {("lifted", t) for t in targets})
        out.append(op)
    return out


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
