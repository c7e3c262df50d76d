"""The A* search's bounds over bit-mask states (`symbolic._search`): which goals may be reached at all, and an
admissible lower bound on the cost to each."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

INF = float("inf")


def _may_reach(start: int, target: tuple[int, int], steps: list, m: Any, chosen: list[int]) -> bool:
    """Whether a goal may be reached at all: its atoms that must hold are reachable ignoring delete effects and
    negative preconditions (a relaxation: a goal it rules out no plan reaches), and each atom that must not hold
    is absent at the start or deleted by some step. A failure branch that can never merge is pruned here
    instead of searching until the budget runs out."""
    pos, neg = target
    reach, changed = start, True
    while changed and reach & pos != pos:
        changed = False
        for pre, _, _, add, _, _ in steps:
            if reach & pre == pre and add & ~reach:
                reach |= add
                changed = True
    deletable = 0
    for i in chosen:
        deletable |= m.deletes[i]
    return reach & pos == pos and not (neg & start & ~deletable)


def _achiever_bounds(goal: Any, table: Any, m: Any, searched: int
                     ) -> tuple[int, int, list[tuple[float, int, bool, int]]]:
    """A* heuristic's table for one goal: its masks, and per literal (dearest first) the cheapest step that
    makes it true (adds a needed atom, deletes a forbidden one), the atom's bit, whether it must be present,
    and the steps that can make it true (a bit per operator of the table, only those `searched`)."""
    out = []
    for atoms, present in ((goal[0], True), (goal[1], False)):
        for a in atoms:
            b = m.bit[a]
            makers = searched & (table.adders.get(a, 0) if present else
                                 sum(1 << i for i in range(len(table.ops)) if not m.keep[i] & b))
            out.append((min((table.ops[i].cost for i in _bits(makers)), default=INF), b, present, makers))
    out.sort(key=lambda x: -x[0])
    return m.of(goal[0]), m.of(goal[1]), out


def _bound(s: int, literals: list[tuple[float, int, bool, int]]) -> float:
    """A lower bound on the cost from state `s` to the goal of `literals` (`_achiever_bounds`): the missing
    literals taken dearest first, each counted when none of the steps that make it true could make one already
    counted true. No step serves two counted literals, so a plan needs a distinct step for each, and the sum of
    their cheapest costs never overestimates (admissible: plans stay cheapest). It is at least the dearest
    missing literal's cost, the bound this planner used before: a rearrange-table plan grasps, carries and
    places each utensil, and with the dearest step alone A* walked five times as many states."""
    total, used = 0.0, 0
    for cost, b, present, makers in literals:
        if ((not s & b) if present else s & b) and not makers & used:
            total += cost
            used |= makers
    return total


def _bits(x: int) -> Iterable[int]:
    """The indices of the set bits of `x`."""
    while x:
        low = x & -x
        yield low.bit_length() - 1
        x ^= low
