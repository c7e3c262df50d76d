"""Where a recovery branch merges back into the nominal graph, and the plan to get there.

Searches are cached within one `embedded_arrange` call (`clear()` at its start): a drop and a slip on
the same edge leave the same state, so half the searches were repeats.
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.agentchord.symbolic import PlanningError, State, plan, plan_each
from kintsugi.taskgraph.model import TaskGraph

RELEASE_COST = 10.0
"""Control steps of a recovery that only opens the hand (the failure already reached the merge node)."""
_NOMINAL: dict[int, Any] = {}
"""The nominal edges as a networkx DiGraph, per graph within one `embedded_arrange` call (cleared at its
start): every branch's merge search and `landed` walk them."""


def _nominal(graph: TaskGraph) -> Any:
    import networkx as nx

    if id(graph) not in _NOMINAL:
        _NOMINAL[id(graph)] = nx.DiGraph((e.source, e.target) for e in graph.edges if e.kind == "nominal")
    return _NOMINAL[id(graph)]


_MERGES: dict[tuple, tuple[str, list] | str] = {}
"""`_merge`'s answers within one `embedded_arrange` call (cleared at its start): a drop and a slip on the same
edge leave the same state, so half the searches were repeats."""


def _merge(start: State, edge: Any, graph: TaskGraph, facts: dict[str, State], ops: list,
           ctg: dict[str, float]) -> tuple[str, list]:
    """The merge node and the plan to it: of the failed edge's target and every node after it, the one whose
    facts the planner reaches for the least cost plus its own cost-to-go (the earliest on a tie, so a branch
    never duplicates the nominal graph). A plan of no steps (the failure already left that node's facts
    true, e.g. an object dropped upright where it was to be placed) merges by releasing the hand."""
    key = (id(graph), id(ops), start, edge.target)
    if key not in _MERGES:
        try:
            _MERGES[key] = _search_merge(start, edge, graph, facts, ops, ctg)
        except PlanningError as exc:
            _MERGES[key] = str(exc)
    found = _MERGES[key]
    if isinstance(found, str):
        raise PlanningError(found)
    return found


def _nominal_merge(start: State, edge: Any, graph: TaskGraph, facts: dict[str, State], ops: list
                   ) -> tuple[str, list] | None:
    """The merge when the failure left the facts of a nominal node before the failed edge's target (a grasp
    that missed, an object that fell back where it lay), else None. The nominal plan on from that node is a
    cheapest plan to the goal (a suffix of the embedded composer's cheapest plan; a model's graph may be
    dearer, and then this merge is a good one, not always the best), so no merge beats its total, and the
    target, the earliest candidate, merges on a tie: only the plan to the target is searched, not one to every
    later node (the two earliest failures of rearrange-table planned the whole task for that, 150 ms of the
    arranger's 320). The branches are the same (`tests/methods/agentchord/test_arranger_merge.py`)."""
    import networkx as nx

    if not any(facts[n] == start for n in nx.ancestors(_nominal(graph), edge.target)):
        return None
    steps = plan(start, (facts[edge.target], frozenset()), ops)
    return (edge.target, steps) if steps else None


def _search_merge(start: State, edge: Any, graph: TaskGraph, facts: dict[str, State], ops: list,
                  ctg: dict[str, float]) -> tuple[str, list]:
    import networkx as nx

    found = _nominal_merge(start, edge, graph, facts, ops)
    if found is not None:
        return found
    best = None
    later = [edge.target, *nx.descendants(_nominal(graph), edge.target)]
    for w, steps in zip(later, plan_each(start, [(facts[w], frozenset()) for w in later], ops)):
        if steps is None:
            continue
        key = (sum(op.cost for op in steps) + (RELEASE_COST if not steps else 0.0) + ctg[w], -ctg[w])
        if best is None or key < best[0]:
            best = (key, w, steps)
    if best is None:
        raise PlanningError(f"no node from {edge.target!r} on can be reached from the state the failure leaves")
    return best[1], best[2]


def clear() -> None:
    """Forget the cached graphs and searches (a new arrangement starts)."""
    _MERGES.clear()
    _NOMINAL.clear()
