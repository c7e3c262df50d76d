"""Property tests of the symbolic planner behind the embedded composer and arranger: on random small domains
and random states, every plan it returns is executable and reaches the goal, it is as cheap as an independent
shortest-path search over the whole state space (networkx), and it says "no plan" exactly when there is none."""

from __future__ import annotations

import itertools

import networkx as nx
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from kintsugi.methods.agentchord.symbolic import OpTable, PlanningError, ground, parse_literals, plan, plan_each, satisfies
from kintsugi.methods.agentchord.types import Domain, OperatorSpec, PredicateSpec

PREDS = ["p", "q", "r", "s"]
OBJS = ["a", "b"]
ATOMS = [(p, o) for p in PREDS for o in OBJS]


def _lit(draw, positive_only: bool = False) -> str:
    p = draw(st.sampled_from(PREDS))
    neg = False if positive_only else draw(st.booleans())
    return ("not " if neg else "") + f"{p}(?x)"


@st.composite
def domains(draw) -> Domain:
    ops = []
    for i in range(draw(st.integers(1, 5))):
        ops.append(OperatorSpec(
            name=f"op{i}", params={"?x": "object"},
            pre=[_lit(draw) for _ in range(draw(st.integers(0, 2)))],
            add=[_lit(draw, True) for _ in range(draw(st.integers(1, 2)))],
            delete=[_lit(draw, True) for _ in range(draw(st.integers(0, 2)))],
            actions=[{"name": "wait", "args": {}}], cost=float(draw(st.integers(1, 9)))))
    return Domain(predicates=[PredicateSpec(name=p, params=["object"]) for p in PREDS], operators=ops)


states = st.frozensets(st.sampled_from(ATOMS))


def _oracle(domain: Domain, initial, goal) -> float | None:
    """Cheapest cost to a goal state by Dijkstra over the full (tiny) state graph, or None."""
    ops = ground(domain, [], OBJS)
    g = nx.DiGraph()
    every = [frozenset(c) for n in range(len(ATOMS) + 1) for c in itertools.combinations(ATOMS, n)]
    for s in every:
        for op in ops:
            if op.applicable(s):
                t = op.apply(s)
                if not g.has_edge(s, t) or g[s][t]["weight"] > op.cost:
                    g.add_edge(s, t, weight=op.cost)
    g.add_node(initial)
    dist = nx.single_source_dijkstra_path_length(g, initial)
    costs = [c for s, c in dist.items() if satisfies(s, goal)]
    return min(costs) if costs else None


@settings(max_examples=150)
@given(domain=domains(), initial=states, goal_atoms=st.lists(st.sampled_from(ATOMS), min_size=1, max_size=3),
       negate=st.lists(st.booleans(), min_size=3, max_size=3))
def test_plans_are_valid_optimal_and_complete(domain, initial, goal_atoms, negate) -> None:
    texts = [("not " if n else "") + f"{p}({o})" for (p, o), n in zip(goal_atoms, negate)]
    goal = parse_literals(texts, domain)
    best = _oracle(domain, initial, goal)
    ops = ground(domain, [], OBJS)
    try:
        steps = plan(initial, goal, ops)
    except PlanningError:
        assert best is None
        return
    assert best is not None
    s = initial
    for op in steps:
        assert op.applicable(s)
        s = op.apply(s)
    assert satisfies(s, goal)
    assert sum(op.cost for op in steps) == pytest.approx(best)
    assert [op.label for op in plan(initial, goal, ops)] == [op.label for op in steps]  # deterministic


def test_wildcard_deletes_remove_every_match() -> None:
    domain = Domain(predicates=[PredicateSpec(name="over", params=["object", "object"]),
                                PredicateSpec(name="free", params=["object"])],
                    operators=[OperatorSpec(name="put", params={"?x": "object"}, pre=[], add=["free(?x)"],
                                            delete=["over(?x, _)"], actions=[{"name": "wait"}], cost=1)])
    op = next(o for o in ground(domain, [], ["a", "b", "c"]) if o.label == "put(a)")
    assert op.apply(frozenset({("over", "a", "b"), ("over", "a", "c"), ("over", "b", "a")})) == \
        frozenset({("over", "b", "a"), ("free", "a")})


@pytest.mark.parametrize("bad, message", [
    ({"pre": ["holding(?y)"]}, r"parameter \?y .* is not declared"),
    ({"pre": ["nosuch(?x)"]}, "unknown predicate 'nosuch'"),
    ({"add": ["not free(?x)"]}, "effects must be positive"),
    ({"pre": ["free(_)"]}, "allowed in delete effects only"),
])
def test_malformed_operators_are_named(bad: dict, message: str) -> None:
    spec = {"name": "op", "params": {"?x": "object"}, "pre": [], "add": ["free(?x)"], "delete": [],
            "actions": [{"name": "wait"}], "cost": 1.0} | bad
    domain = Domain(predicates=[PredicateSpec(name="free", params=["object"]),
                                PredicateSpec(name="holding", params=["object"])],
                    operators=[OperatorSpec.model_validate(spec)])
    with pytest.raises(PlanningError, match=message):
        ground(domain, [], ["a"])


def test_operators_that_cannot_matter_are_not_searched() -> None:
    """A goal no operator can help with fails at once as never achievable, not after the whole budget."""
    domain = Domain(predicates=[PredicateSpec(name=f"b{i}", params=[]) for i in range(12)] +
                    [PredicateSpec(name="never", params=[])],
                    operators=[OperatorSpec(name=f"set{i}", params={}, add=[f"b{i}()"], actions=[{"name": "w"}],
                                            cost=1) for i in range(12)])
    with pytest.raises(PlanningError, match="never achievable: never"):
        plan(frozenset(), parse_literals(["never()"], domain), ground(domain, [], []), max_expansions=100)


def test_a_search_over_budget_gives_up_with_a_clear_error() -> None:
    domain = Domain(predicates=[PredicateSpec(name=f"b{i}", params=[]) for i in range(12)] +
                    [PredicateSpec(name="never", params=[])],
                    operators=[OperatorSpec(name=f"set{i}", params={}, add=[f"b{i}()"], actions=[{"name": "w"}],
                                            cost=1) for i in range(12)] +
                              [OperatorSpec(name="finish", params={}, pre=[f"b{i}()" for i in range(12)],
                                            add=["never()"], actions=[{"name": "w"}], cost=1)])
    # Every set-op is relevant (finish needs them all): uniform-cost search walks the 4,096 subsets.
    with pytest.raises(PlanningError, match="no plan within 100 expanded states"):
        plan(frozenset(), parse_literals(["never()"], domain), ground(domain, [], []), max_expansions=100)


@settings(max_examples=100)
@given(domain=domains(), initial=states,
       goals=st.lists(st.lists(st.sampled_from(ATOMS), min_size=1, max_size=3), min_size=1, max_size=4))
def test_one_search_for_many_goals_gives_each_goal_its_own_plan(domain, initial, goals) -> None:
    parsed = [parse_literals([f"{p}({o})" for p, o in g], domain) for g in goals]
    ops = ground(domain, [], OBJS)
    for goal, steps in zip(parsed, plan_each(initial, parsed, ops)):
        try:
            alone = plan(initial, goal, ops)
        except PlanningError:
            assert steps is None
            continue
        assert steps is not None
        assert sum(op.cost for op in steps) == pytest.approx(sum(op.cost for op in alone))


@settings(max_examples=60)
@given(domain=domains(), cases=st.lists(st.tuples(states, st.lists(st.sampled_from(ATOMS), min_size=1, max_size=3)),
                                        min_size=1, max_size=6))
def test_one_table_for_many_searches_plans_as_fresh_lists_do(domain, cases) -> None:
    """The arranger builds the operators' masks once and searches them many times: every plan is the one a
    fresh list gives, so nothing a search adds (bits for atoms no operator names) leaks into the next."""
    ops = ground(domain, [], OBJS)
    table = OpTable(ops)
    for initial, atoms in cases:
        goal = parse_literals([f"{p}({o})" for p, o in atoms], domain)
        try:
            fresh = [op.label for op in plan(initial, goal, ops)]
        except PlanningError as exc:
            with pytest.raises(PlanningError, match=str(exc).split(";")[0]):
                plan(initial, goal, table)
            continue
        assert [op.label for op in plan(initial, goal, table)] == fresh


def test_a_wild_delete_removes_an_atom_only_the_state_names() -> None:
    """`over(a, z)` with z no operator names: the table gives it a bit for that search, and a wild delete
    `over(?x, _)` must still remove it, or a goal that forbids it is never met."""
    domain = Domain(predicates=[PredicateSpec(name="over", params=["object", "object"]),
                                PredicateSpec(name="free", params=["object"])],
                    operators=[OperatorSpec(name="put", params={"?x": "object"}, pre=[], add=["free(?x)"],
                                            delete=["over(?x, _)"], actions=[{"name": "wait"}], cost=1)])
    table = OpTable(ground(domain, [], ["a", "b"]))
    goal = parse_literals(["not over(a, z)"], domain)
    for _ in range(2):  # the second search starts from the table again, not from the first one's bits
        assert [op.label for op in plan(frozenset({("over", "a", "z")}), goal, table)] == ["put(a)"]



def test_the_bound_adds_literals_no_one_step_makes_together() -> None:
    """mk_p(x) makes p(x) (3), mk_q(x) makes q(x) (2), mk_pq(x) makes both (5). p(a) and p(b) need two steps,
    so the bound adds them (6); p(a) and q(a) could come from one mk_pq(a), so it counts only the dearer (3)."""
    from kintsugi.methods.agentchord.symbolic import _achiever_bounds, _bound

    def op(name: str, add: list[str], cost: float) -> OperatorSpec:
        return OperatorSpec(name=name, params={"?x": "object"}, add=add, actions=[{"name": "w"}], cost=cost)

    domain = Domain(predicates=[PredicateSpec(name=p, params=["object"]) for p in ("p", "q")],
                    operators=[op("mk_p", ["p(?x)"], 3), op("mk_q", ["q(?x)"], 2), op("mk_pq", ["p(?x)", "q(?x)"], 5)])
    table = OpTable(ground(domain, [], ["a", "b"]))
    every = (1 << len(table.ops)) - 1

    def bound(goal: list[str], state: frozenset = frozenset()) -> float:
        g = parse_literals(goal, domain)
        m = table.masks.extended(state | g[0], table.ops)
        return _bound(m.of(state), _achiever_bounds(g, table, m, every)[2])

    assert bound(["p(a)", "p(b)"]) == 6
    assert bound(["p(a)", "q(a)"]) == 3
    assert bound(["p(a)", "q(a)", "p(b)", "q(b)"]) == 6
    assert bound(["p(a)", "p(b)"], frozenset({("p", "a")})) == 3
    assert plan(frozenset(), parse_literals(["p(a)", "q(a)"], domain), table)[0].label == "mk_pq(a)"
