"""A small STRIPS planner: typed operators grounded over the scene's arms and objects, cheapest plan by
A* search (an admissible bound: the missing goal literals no one step makes together, added up, `_bound`). The
embedded composer plans the nominal graph with it and the embedded arranger plans each recovery branch (from the
state a failure leaves to a merge node) with it, over one `OpTable` of the operators' bit masks for all its searches.

States are frozensets of ground atoms `("holding", "right", "bottle")` under the closed-world assumption.
"""

from __future__ import annotations

import heapq
import itertools
import re
from collections.abc import Iterable
from dataclasses import dataclass

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.agentchord.bounds import _achiever_bounds, _bits, _bound, _may_reach  # noqa: F401
from kintsugi.methods.agentchord.types import Domain, OperatorSpec, parse_atom

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
    wrong arity or unbound parameters raise PlanningError naming the literal. A domain alias (`held_up(x)`)
    stands for its literals (a negated alias is refused: it would be a disjunction)."""
    arity = {p.name: len(p.params) for p in domain.predicates}
    pos: set[Atom] = set()
    neg: set[Atom] = set()
    texts = expand_aliases(texts, domain, where)
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


def expand_aliases(texts: list[str], domain: Domain, where: str = "goal") -> list[str]:
    """Literals with each alias (`Domain.aliases`) replaced by the literals it stands for."""
    if not domain.aliases:
        return list(texts)
    out: list[str] = []
    for text in texts:
        try:
            positive, name, args = parse_atom(text)
        except ValueError as exc:
            raise PlanningError(f"{where}: {exc}") from None
        if name not in domain.aliases:
            out.append(text)
            continue
        body = domain.aliases[name]
        need = list(dict.fromkeys(a for t in body for a in parse_atom(t)[2] if a.startswith("?")))
        if len(args) != len(need):
            raise PlanningError(f"{where}: {name} takes {len(need)} argument(s), {text!r} gives {len(args)}")
        if not positive:
            raise PlanningError(f"{where}: {text!r}: `not` before {name} (which stands for "
                                f"{', '.join(body)}) is not a goal this planner can state")
        for t in body:
            for p, a in zip(need, args):
                t = re.sub(rf"\{p}\b", a, t)
            out.append(t)
    return out


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


class OpTable:
    """Ground operators compiled once into bit masks over every atom they name, for many searches over one
    list: the arranger searches the same operators about thirty times per compile, and rebuilding these masks
    in every search was a third of its time. Atoms a search meets that no operator names (in its initial state
    or its goals) get bits of their own in that search (`_Masks.extended`)."""

    def __init__(self, ops: list[GroundOp]) -> None:
        self.ops = list(ops)
        bit: dict[Atom, int] = {}
        for a in itertools.chain(*(op.add for op in self.ops),
                                 *(op.pre_pos | op.pre_neg | op.delete for op in self.ops)):
            bit.setdefault(a, 1 << len(bit))
        by_predicate: dict[str, list[Atom]] = {}
        for a in bit:
            by_predicate.setdefault(a[0], []).append(a)
        self.masks = m = _Masks(bit, [], [], [], [], [])
        for op in self.ops:
            wiped = {a for p in op._wild_predicates for a in by_predicate.get(p, ())  # type: ignore[attr-defined]
                     if op.wild_deletes(a)}
            m.pre_pos.append(m.of(op.pre_pos))
            m.pre_neg.append(m.of(op.pre_neg))
            m.keep.append(~m.of((op.delete | wiped) - op.add))
            m.add.append(m.of(op.add))
            m.deletes.append(m.of(op.delete | wiped))
        # Each operator filed under one of its positive preconditions (the one with the most arguments, the rarest
        # true: holding(left, fork) rather than hand_empty(left)): a state tries only the operators filed under an
        # atom it holds, in their order (so the plans, ties included, are those of trying all of them).
        self.file_bit = [bit[max(sorted(op.pre_pos), key=len)] if op.pre_pos else 0 for op in self.ops]
        self.adders: dict[Atom, int] = {}
        """atom -> the operators that add it, a bit per operator (by its index here)."""
        for i, op in enumerate(self.ops):
            for a in op.add:
                self.adders[a] = self.adders.get(a, 0) | 1 << i

    def relevant(self, goal: Goal, m: "_Masks") -> list[int]:
        """The indices of the operators that can matter for the goal, in their order: those that add an atom
        the goal or a relevant operator needs true, or delete one they need false (backward, to a fixpoint).
        Dropping the rest keeps every cheapest plan (with positive costs, a step that does neither only adds
        cost) and shrinks the search: the arranger's plans for rearrange-table went from minutes to seconds."""
        need_true, need_false = m.of(goal[0]), m.of(goal[1])
        keep = [False] * len(self.ops)
        changed = True
        while changed:
            changed = False
            for i in range(len(self.ops)):
                if not keep[i] and (m.add[i] & need_true or m.deletes[i] & need_false):
                    keep[i] = changed = True
                    need_true |= m.pre_pos[i]
                    need_false |= m.pre_neg[i]
        return [i for i, k in enumerate(keep) if k]


@dataclass
class _Masks:
    """An `OpTable`'s atom bits and per-operator masks: preconditions, what applying keeps (`keep`, ANDed),
    adds, and what it deletes (exact or by a wild pattern; for relevance)."""

    bit: dict[Atom, int]
    pre_pos: list[int]
    pre_neg: list[int]
    keep: list[int]
    add: list[int]
    deletes: list[int]

    def of(self, atoms: Iterable[Atom]) -> int:
        return sum(self.bit[a] for a in set(atoms))

    def extended(self, atoms: Iterable[Atom], ops: list[GroundOp]) -> "_Masks":
        """These masks with a bit for each atom no operator names (a wild delete may still remove it); self
        when there is none."""
        new = [a for a in dict.fromkeys(atoms) if a not in self.bit]
        if not new:
            return self
        out = _Masks(dict(self.bit), self.pre_pos, self.pre_neg, list(self.keep), self.add, list(self.deletes))
        for a in new:
            b = out.bit[a] = 1 << len(out.bit)
            for i, op in enumerate(ops):
                if op.wild_deletes(a):
                    out.deletes[i] |= b
                    if a not in op.add:
                        out.keep[i] &= ~b
        return out


def _table(ops: "list[GroundOp] | OpTable") -> OpTable:
    return ops if isinstance(ops, OpTable) else OpTable(ops)


def plan(initial: State, goal: Goal, ops: "list[GroundOp] | OpTable", max_expansions: int = MAX_EXPANSIONS
         ) -> list[GroundOp]:
    """The cheapest operator sequence from `initial` to a state satisfying `goal` (A* search; ties broken by
    insertion order, so the answer is deterministic). `ops`: a list, or an `OpTable` built once for many plans."""
    table = _table(ops)
    (steps,), over_budget = _search(initial, [goal], table, max_expansions)
    if steps is not None:
        return steps
    if over_budget:
        raise PlanningError(f"no plan within {max_expansions} expanded states; the domain is too loose "
                            "or the goal unreachable")
    missing = ", ".join(sorted(atom_text(a) for a in goal[0] - _reachable_atoms(initial, relevant(table, goal))))
    raise PlanningError(f"the goal cannot be reached from the observed state with these actions; "
                        f"never achievable: {missing or '(a combination)'}")


def plan_each(initial: State, goals: list[Goal], ops: "list[GroundOp] | OpTable",
              max_expansions: int = MAX_EXPANSIONS) -> list[list[GroundOp] | None]:
    """The cheapest plan to each goal (None: none found within the budget), from one search instead of one
    per goal: the arranger asks for every node after a failure at once (the same plans as `plan`, which
    the planner tests check)."""
    return _search(initial, goals, _table(ops), max_expansions * max(1, len(goals)))[0]


def _search(initial: State, goals: list[Goal], table: OpTable, max_expansions: int
            ) -> tuple[list[list[GroundOp] | None], bool]:
    """A* search over the operators relevant to the goals until every goal is met (the first state popped that
    meets one ends the cheapest plan to it: the bound is the least over the goals still waiting, so it never
    overestimates the cost to any of them); (plans, whether the budget ran out).

    States are searched as bit masks over every atom a state can hold (the initial state's and the
    operators' effects): applying an operator, testing its preconditions and a goal are then integer
    operations. As frozensets they were most of a compile (a wild delete alone tested every atom of every
    state); the expansions, and so the plans, are the same."""
    found: list[list[GroundOp] | None] = [None] * len(goals)
    waiting = list(range(len(goals)))
    m = table.masks.extended(itertools.chain(initial, *(g[0] | g[1] for g in goals)), table.ops)
    need = (frozenset().union(*(g[0] for g in goals)), frozenset().union(*(g[1] for g in goals)))
    chosen = table.relevant(need, m)
    steps_of = [(m.pre_pos[i], m.pre_neg[i], m.keep[i], m.add[i], table.ops[i].cost, table.ops[i]) for i in chosen]
    filed: dict[int, list[int]] = {}
    always: list[int] = []
    for j, i in enumerate(chosen):
        if table.file_bit[i]:
            filed.setdefault(table.file_bit[i], []).append(j)
        else:
            always.append(j)
    keys = list(filed.items())
    targets = [(m.of(g[0]), m.of(g[1])) for g in goals]
    searched = sum(1 << i for i in chosen)
    bounds = [_achiever_bounds(g, table, m, searched) for g in goals]

    def h(s: int) -> float:
        least = INF
        for i in waiting:
            pos, neg, literals = bounds[i]
            if s & pos == pos and not s & neg:
                return 0.0
            least = min(least, _bound(s, literals))
        return least if waiting else 0.0

    start = m.of(initial)
    waiting = [i for i in waiting if _may_reach(start, targets[i], steps_of, m, chosen)]
    if not waiting:  # every goal is out of reach even ignoring deletes: no search (it would use its budget up)
        return found, False
    counter = itertools.count()
    frontier: list[tuple[float, int, float, int]] = [(h(start), next(counter), 0.0, start)]
    best: dict[int, float] = {start: 0.0}
    parent: dict[int, tuple[int, GroundOp]] = {}
    expanded = 0
    while frontier:
        _, _, cost, s = heapq.heappop(frontier)
        if cost > best.get(s, float("inf")):
            continue
        met = [i for i in waiting if s & targets[i][0] == targets[i][0] and not s & targets[i][1]]
        if met:
            steps: list[GroundOp] = []
            t = s
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
        tried = always + [i for k, idx in keys if s & k for i in idx]
        tried.sort()
        for i in tried:
            pos, neg, keep, add, op_cost, op = steps_of[i]
            if s & pos != pos or s & neg:
                continue
            t = (s & keep) | add
            c = cost + op_cost
            if c < best.get(t, float("inf")):
                best[t] = c
                parent[t] = (s, op)
                f = c + h(t)
                if f < float("inf"):
                    heapq.heappush(frontier, (f, next(counter), c, t))
    return found, False


def relevant(ops: "list[GroundOp] | OpTable", goal: Goal) -> list[GroundOp]:
    """The operators that can matter for the goal, in their order (`OpTable.relevant`)."""
    table = _table(ops)
    m = table.masks.extended(goal[0] | goal[1], table.ops)
    return [table.ops[i] for i in table.relevant(goal, m)]


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
