"""A small STRIPS planner: typed operators grounded over the scene's arms and objects, cheapest plan by
A* search (an admissible bound: the dearest single step a missing goal literal needs). The embedded composer plans the nominal graph with it and the embedded arranger plans
each recovery branch (from the state a failure leaves to a merge node) with it.

States are frozensets of ground atoms `("holding", "right", "bottle")` under the closed-world assumption.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

from kintsugi.errors import ReasoningError
from kintsugi.reasoning.taskgraph_types import Domain, OperatorSpec, parse_atom

Atom = tuple[str, ...]
State = frozenset[Atom]
INF = float("inf")
MAX_EXPANSIONS = 50_000
"""A search that expands more states than this gives up (a domain too loose for the embedded planner)."""


class PlanningError(ReasoningError):
    """No plan: unknown predicate, unreachable goal, or a search that exceeded its budget."""


@dataclass(frozen=True)
class GroundOp:
    name: str
    binding: tuple[tuple[str, str], ...]
    """(?param, value) in declaration order."""
    pre_pos: frozenset[Atom]
    pre_neg: frozenset[Atom]
    add: frozenset[Atom]
    delete: frozenset[Atom]
    cost: float
    spec: OperatorSpec
    wild: tuple[Atom, ...] = ()
    """Delete patterns with `_` (any value) in some places, e.g. over(bottle, _)."""

    def __post_init__(self) -> None:
        # The predicates the wild patterns name: an atom of any other predicate cannot match (most of a state),
        # so apply() skips the pattern test for it; the search spent 70 % of a compile in that test.
        object.__setattr__(self, "_wild_predicates", frozenset(w[0] for w in self.wild))
        object.__setattr__(self, "_wild_hits", {})

    def wild_deletes(self, atom: Atom) -> bool:
        """Whether a wild delete pattern removes `atom` (remembered: the arranger's searches meet the same
        atoms again and again)."""
        hits = self._wild_hits  # type: ignore[attr-defined]
        if atom not in hits:
            hits[atom] = atom[0] in self._wild_predicates and any(matches(atom, w) for w in self.wild)  # type: ignore[attr-defined]
        return hits[atom]

    @property
    def label(self) -> str:
        return f"{self.name}({', '.join(v for _, v in self.binding)})"

    def applicable(self, s: State) -> bool:
        return self.pre_pos <= s and not (self.pre_neg & s)

    def apply(self, s: State) -> State:
        if self.wild:
            s = frozenset(a for a in s if not self.wild_deletes(a))
        return (s - self.delete) | self.add


def matches(atom: Atom, pattern: Atom) -> bool:
    return len(atom) == len(pattern) and all(p in ("_", a) for a, p in zip(atom, pattern))


def atom_text(a: Atom) -> str:
    return f"{a[0]}({', '.join(a[1:])})"


def parse_literals(texts: list[str], domain: Domain, binding: dict[str, str] | None = None,
                   where: str = "goal", allow_wild: bool = False) -> tuple[frozenset[Atom], frozenset[Atom]]:
    """Literals -> (positive atoms, negated atoms), parameters filled from `binding`; unknown predicates,
    wrong arity or unbound parameters raise PlanningError naming the literal."""
    arity = {p.name: len(p.params) for p in domain.predicates}
    pos: set[Atom] = set()
    neg: set[Atom] = set()
    for text in texts:
        try:
            positive, name, args = parse_atom(text)
        except ValueError as exc:
            raise PlanningError(f"{where}: {exc}") from None
        if name not in arity:
            raise PlanningError(f"{where}: unknown predicate {name!r} in {text!r}; known: {', '.join(sorted(arity))}")
        if len(args) != arity[name]:
            raise PlanningError(f"{where}: {name} takes {arity[name]} argument(s), {text!r} gives {len(args)}")
        vals = []
        for a in args:
            if a.startswith("?"):
                if binding is None or a not in binding:
                    raise PlanningError(f"{where}: parameter {a} in {text!r} is not declared")
                a = binding[a]
            vals.append(a)
        if "_" in vals and not (allow_wild and positive):
            raise PlanningError(f"{where}: `_` (any) is allowed in delete effects only, not in {text!r}")
        (pos if positive else neg).add((name, *vals))
    return frozenset(pos), frozenset(neg)


def ground(domain: Domain, arms: list[str], objects: list[str], places: list[str] = ()) -> list[GroundOp]:
    """Every operator instance over the given arms, objects and places (the goal's other constants: regions,
    directions), with distinct objects and distinct arms per instance (a handover needs two arms)."""
    pools = {"arm": arms, "object": objects, "place": list(places)}
    out: list[GroundOp] = []
    for op in domain.operators:
        names = list(op.params)
        for values in itertools.product(*(pools[op.params[n]] for n in names)):
            objs = [v for n, v in zip(names, values) if op.params[n] == "object"]
            arms_ = [v for n, v in zip(names, values) if op.params[n] == "arm"]
            if len(set(objs)) != len(objs) or len(set(arms_)) != len(arms_):
                continue
            b = dict(zip(names, values))
            where = f"operator {op.name}"
            pre_pos, pre_neg = parse_literals(op.pre, domain, b, where)
            add, add_neg = parse_literals(op.add, domain, b, where)
            delete, del_neg = parse_literals(op.delete, domain, b, where, allow_wild=True)
            if add_neg or del_neg:
                raise PlanningError(f"{where}: effects must be positive atoms (list removals under `delete`)")
            wild = tuple(a for a in delete if "_" in a)
            exact = frozenset(a for a in delete if "_" not in a) - add
            out.append(GroundOp(op.name, tuple(b.items()), pre_pos, pre_neg, add, exact, op.cost, op, wild))
    return out


def satisfies(s: State, goal: tuple[frozenset[Atom], frozenset[Atom]]) -> bool:
    pos, neg = goal
    return pos <= s and not (neg & s)


Goal = tuple[frozenset[Atom], frozenset[Atom]]


def plan(initial: State, goal: Goal, ops: list[GroundOp], max_expansions: int = MAX_EXPANSIONS) -> list[GroundOp]:
    """The cheapest operator sequence from `initial` to a state satisfying `goal` (A* search; ties broken by
    insertion order, so the answer is deterministic)."""
    ops = relevant(ops, goal)
    (steps,), over_budget = _search(initial, [goal], ops, max_expansions)
    if steps is not None:
        return steps
    if over_budget:
        raise PlanningError(f"no plan within {max_expansions} expanded states; the domain is too loose "
                            "or the goal unreachable")
    missing = ", ".join(sorted(atom_text(a) for a in goal[0] - _reachable_atoms(initial, ops))) or "(a combination)"
    raise PlanningError(f"the goal cannot be reached from the observed state with these actions; "
                        f"never achievable: {missing}")


def plan_each(initial: State, goals: list[Goal], ops: list[GroundOp], max_expansions: int = MAX_EXPANSIONS
              ) -> list[list[GroundOp] | None]:
    """The cheapest plan to each goal (None: none found within the budget), from one search instead of one
    per goal: the arranger asks for every node after a failure at once (the same plans as `plan`, which
    the planner tests check)."""
    need = (frozenset().union(*(g[0] for g in goals)), frozenset().union(*(g[1] for g in goals)))
    return _search(initial, goals, relevant(ops, need), max_expansions * max(1, len(goals)))[0]


def _search(initial: State, goals: list[Goal], ops: list[GroundOp], max_expansions: int
            ) -> tuple[list[list[GroundOp] | None], bool]:
    """A* search until every goal is met (the first state popped that meets one ends the cheapest plan to it:
    the bound is the least over the goals still waiting, so it never overestimates the cost to any of them);
    (plans, whether the budget ran out).

    States are searched as bit masks over every atom a state can hold (the initial state's and the
    operators' effects): applying an operator, testing its preconditions and a goal are then integer
    operations. As frozensets they were most of a compile (a wild delete alone tested every atom of every
    state); the expansions, and so the plans, are the same."""
    found: list[list[GroundOp] | None] = [None] * len(goals)
    waiting = list(range(len(goals)))
    bit: dict[Atom, int] = {}
    for a in itertools.chain(initial, *(op.add for op in ops), *(op.pre_pos | op.pre_neg | op.delete for op in ops),
                             *(g[0] | g[1] for g in goals)):
        bit.setdefault(a, 1 << len(bit))

    def mask(atoms: frozenset[Atom] | set[Atom]) -> int:
        return sum(bit[a] for a in atoms)

    by_predicate: dict[str, list[Atom]] = {}
    for a in bit:
        by_predicate.setdefault(a[0], []).append(a)
    steps_of = []
    for op in ops:
        gone = set(op.delete) | {a for p in op._wild_predicates for a in by_predicate.get(p, ())  # type: ignore[attr-defined]
                                 if op.wild_deletes(a)}
        steps_of.append((mask(op.pre_pos), mask(op.pre_neg), ~mask(gone - op.add), mask(op.add), op.cost, op))
    # Each operator filed under one of its positive preconditions (the one with the most arguments, the rarest
    # true: holding(left, fork) rather than hand_empty(left)): a state tries only the operators filed under an
    # atom it holds, in their order (so the plans, ties included, are those of trying all of them).
    filed: dict[int, list[int]] = {}
    always: list[int] = []
    for i, op in enumerate(ops):
        if op.pre_pos:
            filed.setdefault(bit[max(sorted(op.pre_pos), key=len)], []).append(i)
        else:
            always.append(i)
    keys = list(filed.items())
    targets = [(mask(g[0]), mask(g[1])) for g in goals]
    cheapest: dict[Atom, float] = {}  # each atom's cheapest adder, one pass over the operators for every goal
    for op in ops:
        for a in op.add:
            if op.cost < cheapest.get(a, INF):
                cheapest[a] = op.cost
    bounds = [_levels(_literal_bounds(g, ops, bit, cheapest)) for g in goals]

    def h(m: int) -> float:
        least = INF
        for i in waiting:
            for cost, pos, neg in bounds[i]:
                if m & pos != pos or m & neg:
                    break
            else:
                return 0.0
            least = min(least, cost)
        return least if waiting else 0.0

    start = mask(initial)
    counter = itertools.count()
    frontier: list[tuple[float, int, float, int]] = [(h(start), next(counter), 0.0, start)]
    best: dict[int, float] = {start: 0.0}
    parent: dict[int, tuple[int, GroundOp]] = {}
    expanded = 0
    while frontier:
        _, _, cost, m = heapq.heappop(frontier)
        if cost > best.get(m, float("inf")):
            continue
        met = [i for i in waiting if m & targets[i][0] == targets[i][0] and not m & targets[i][1]]
        if met:
            steps: list[GroundOp] = []
            t = m
            while t in parent:
                t, op = parent[t]
                steps.append(op)
            for i in met:
                found[i] = steps[::-1]
                waiting.remove(i)
            if not waiting:
                return found, False
        expanded += 1
        if expanded > max_expansions:
            return found, True
        tried = always + [i for k, idx in keys if m & k for i in idx]
        tried.sort()
        for i in tried:
            pos, neg, keep, add, op_cost, op = steps_of[i]
            if m & pos != pos or m & neg:
                continue
            t = (m & keep) | add
            c = cost + op_cost
            if c < best.get(t, float("inf")):
                best[t] = c
                parent[t] = (m, op)
                f = c + h(t)
                if f < float("inf"):
                    heapq.heappush(frontier, (f, next(counter), c, t))
    return found, False


def _literal_bounds(goal: Goal, ops: list[GroundOp], bit: dict[Atom, int], cheapest: dict[Atom, float]
                    ) -> list[tuple[float, int, bool]]:
    """Per goal literal, the cheapest single step that makes it true (adds a needed atom, deletes a forbidden
    one; infinite when none does), as (cost, the atom's bit, whether it must be present), dearest first.
    `cheapest`: each atom's cheapest adder among `ops`."""
    out = [(cheapest.get(a, INF), bit[a], True) for a in goal[0]]
    for a in goal[1]:
        out.append((min((op.cost for op in ops if a in op.delete or op.wild_deletes(a)), default=INF), bit[a], False))
    return sorted(out, key=lambda x: -x[0])


def _levels(literals: list[tuple[float, int, bool]]) -> list[tuple[float, int, int]]:
    """A* heuristic's table: the literals of one cost merged into two masks (must be present, must be absent),
    dearest first. A lower bound on the cost from a state to the goal (admissible, so plans stay cheapest) is the
    cost of the first level with a literal the state lacks: every such literal needs a step of its own, so the
    dearest of those steps at least; infinite when no step makes one of them true. Tested a level at a time, not
    a literal at a time (a fifth of a compile went there; the bound, and so every plan, is the same)."""
    levels: dict[float, list[int]] = {}
    for cost, b, present in literals:
        level = levels.setdefault(cost, [0, 0])
        level[0 if present else 1] |= b
    return [(cost, pos, neg) for cost, (pos, neg) in sorted(levels.items(), key=lambda kv: -kv[0])]


def relevant(ops: list[GroundOp], goal: tuple[frozenset[Atom], frozenset[Atom]]) -> list[GroundOp]:
    """The operators that can matter for the goal, in their order: those that add an atom the goal or a
    relevant operator needs true, or delete one they need false (backward, to a fixpoint). Dropping the rest
    keeps every cheapest plan (with positive costs, a step that does neither only adds cost) and shrinks the
    search: the arranger's plans for rearrange-table went from minutes to seconds."""
    need_true, need_false = set(goal[0]), set(goal[1])
    false_by_predicate: dict[str, set[Atom]] = {}  # a wild delete can only match atoms of its own predicate
    for a in need_false:
        false_by_predicate.setdefault(a[0], set()).add(a)
    keep = [False] * len(ops)
    changed = True
    while changed:
        changed = False
        for i, op in enumerate(ops):
            if keep[i]:
                continue
            helps = (not op.add.isdisjoint(need_true) or not op.delete.isdisjoint(need_false)
                     or any(op.wild_deletes(a) for w in op.wild for a in false_by_predicate.get(w[0], ())))
            if helps:
                keep[i] = changed = True
                need_true |= op.pre_pos
                need_false |= op.pre_neg
                for a in op.pre_neg:
                    false_by_predicate.setdefault(a[0], set()).add(a)
    return [op for op, k in zip(ops, keep) if k]


def _reachable_atoms(initial: State, ops: list[GroundOp]) -> frozenset[Atom]:
    """Relaxed reachability (delete effects ignored): for naming the goal atoms no action can produce."""
    atoms = set(initial)
    changed = True
    while changed:
        changed = False
        for op in ops:
            if op.pre_pos <= atoms and not op.add <= atoms:
                atoms |= op.add
                changed = True
    return frozenset(atoms)
