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

    @property
    def label(self) -> str:
        return f"{self.name}({', '.join(v for _, v in self.binding)})"

    def applicable(self, s: State) -> bool:
        return self.pre_pos <= s and not (self.pre_neg & s)

    def apply(self, s: State) -> State:
        if self.wild:
            named = self._wild_predicates  # type: ignore[attr-defined]
            s = frozenset(a for a in s if a[0] not in named or not any(matches(a, w) for w in self.wild))
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
    (plans, whether the budget ran out)."""
    found: list[list[GroundOp] | None] = [None] * len(goals)
    waiting = list(range(len(goals)))
    # Preconditions as bit masks over the atoms they name: testing every operator on every expanded state
    # was a third of a compile as frozenset comparisons.
    bit = {a: 1 << i for i, a in enumerate({a for op in ops for a in op.pre_pos | op.pre_neg})}
    masks = [(sum(bit[a] for a in op.pre_pos), sum(bit[a] for a in op.pre_neg), op) for op in ops]
    bounds = [_step_bounds(g, ops) for g in goals]

    def h(t: State) -> float:
        return min((_bound(t, goals[i], bounds[i]) for i in waiting), default=0.0)

    counter = itertools.count()
    frontier: list[tuple[float, int, float, State]] = [(h(initial), next(counter), 0.0, initial)]
    best: dict[State, float] = {initial: 0.0}
    parent: dict[State, tuple[State, GroundOp]] = {}
    expanded = 0
    while frontier:
        _, _, cost, s = heapq.heappop(frontier)
        if cost > best.get(s, float("inf")):
            continue
        met = [i for i in waiting if satisfies(s, goals[i])]
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
        m = sum(bit.get(a, 0) for a in s)
        for pos, neg, op in masks:
            if m & pos != pos or m & neg:
                continue
            t = op.apply(s)
            c = cost + op.cost
            if c < best.get(t, float("inf")):
                best[t] = c
                parent[t] = (s, op)
                f = c + h(t)
                if f < float("inf"):
                    heapq.heappush(frontier, (f, next(counter), c, t))
    return found, False


def _step_bounds(goal: Goal, ops: list[GroundOp]) -> tuple[dict[Atom, float], dict[Atom, float]]:
    """Per goal literal, the cheapest single step that makes it true (adds a needed atom, deletes a forbidden
    one); a literal no step makes true is absent."""
    adds: dict[Atom, float] = {}
    dels: dict[Atom, float] = {}
    for op in ops:
        for a in goal[0] & op.add:
            adds[a] = min(adds.get(a, float("inf")), op.cost)
        for a in goal[1]:
            if a in op.delete or any(matches(a, w) for w in op.wild):
                dels[a] = min(dels.get(a, float("inf")), op.cost)
    return adds, dels


def _bound(s: State, goal: Goal, bounds: tuple[dict[Atom, float], dict[Atom, float]]) -> float:
    """A lower bound on the cost from `s` to the goal (A*'s heuristic, admissible so plans stay cheapest): every
    literal it still lacks needs a step of its own, so the dearest of those steps at least; infinite when no
    step makes one of them true."""
    adds, dels = bounds
    need = 0.0
    for a in goal[0]:
        if a not in s:
            need = max(need, adds.get(a, float("inf")))
    for a in goal[1]:
        if a in s:
            need = max(need, dels.get(a, float("inf")))
    return need


def relevant(ops: list[GroundOp], goal: tuple[frozenset[Atom], frozenset[Atom]]) -> list[GroundOp]:
    """The operators that can matter for the goal, in their order: those that add an atom the goal or a
    relevant operator needs true, or delete one they need false (backward, to a fixpoint). Dropping the rest
    keeps every cheapest plan (with positive costs, a step that does neither only adds cost) and shrinks the
    search: the arranger's plans for rearrange-table went from minutes to seconds."""
    need_true, need_false = set(goal[0]), set(goal[1])
    keep = [False] * len(ops)
    changed = True
    while changed:
        changed = False
        for i, op in enumerate(ops):
            if keep[i]:
                continue
            helps = (not op.add.isdisjoint(need_true) or not op.delete.isdisjoint(need_false)
                     or any(matches(a, w) for w in op.wild for a in need_false))
            if helps:
                keep[i] = changed = True
                need_true |= op.pre_pos
                need_false |= op.pre_neg
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
