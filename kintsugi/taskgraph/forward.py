"""The forward-moving recovery principle (Eq. 8): keep a branch only if it does not move away from the goal.

Cost-to-go C(n) is the shortest-path cost from n to the terminal goal on the augmented graph,
weighted by each edge's physical cost. Only edges the conductor can take of its own accord
count: nominal edges and edges leaving recovery nodes. An edge entering a recovery branch from
its failure context runs only when a monitor fires, so it never shortens anyone's cost-to-go
(otherwise a node upstream could look close to the goal through a failure-only shortcut).

A branch is one recovery edge that merges into a nominal node m, reached from failure context
u (the source node of the monitored edge). It is kept iff C(m) <= C(u). Recovery nodes left
with no way back into the nominal graph are dropped, with their entry edges; monitors whose
recovery edge was dropped keep detecting, with recovery None.
"""

from __future__ import annotations

import math

import networkx as nx
from pydantic import BaseModel, ConfigDict

from kintsugi.taskgraph.model import Edge, TaskGraph

_EPS = 1e-9


def traversable(graph: TaskGraph) -> nx.DiGraph:
    """Edges the conductor may choose (not failure-triggered entries), cheapest parallel edge kept."""
    kinds = {n.id: n.kind for n in graph.nodes}
    g = nx.DiGraph()
    g.add_nodes_from(kinds)
    for e in graph.edges:
        if e.kind == "recovery" and kinds[e.source] == "nominal":
            continue
        if not g.has_edge(e.source, e.target) or g[e.source][e.target]["weight"] > e.cost:
            g.add_edge(e.source, e.target, weight=e.cost)
    return g


def cost_to_go(graph: TaskGraph) -> dict[str, float]:
    """C(n, goal) for every node; inf where the goal cannot be reached."""
    dist = nx.single_source_dijkstra_path_length(traversable(graph).reverse(copy=False), graph.goal, weight="weight")
    return {n.id: float(dist.get(n.id, math.inf)) for n in graph.nodes}


def next_edge(graph: TaskGraph, node_id: str, ctg: dict[str, float] | None = None) -> Edge | None:
    """The outgoing edge (nominal, or recovery out of a recovery node) on a cheapest path to the goal."""
    ctg = ctg if ctg is not None else cost_to_go(graph)
    kind = graph.node(node_id).kind
    best, best_cost = None, math.inf
    for e in graph.out_edges(node_id):
        if kind == "nominal" and e.kind == "recovery":
            continue
        c = e.cost + ctg[e.target]
        if c < best_cost:
            best, best_cost = e, c
    return best


def open_edges(graph: TaskGraph, node_id: str, features: object) -> list[Edge]:
    """The outgoing edges whose guards hold on `features` (an undecided guard, NaN, does not hold)."""
    return [e for e in graph.out_edges(node_id) if all(c.evaluate(features) <= 0.0 for c in e.guard)]


def guarded_next_edge(graph: TaskGraph, node_id: str, features: object, ctg: dict[str, float] | None = None
                      ) -> tuple[Edge | None, bool]:
    """`next_edge` among the edges whose guards hold now; (edge, True) when one does, else the unguarded
    choice and False (the caller records that no branch matched what it sees)."""
    ctg = ctg if ctg is not None else cost_to_go(graph)
    if not any(e.guard for e in graph.out_edges(node_id)):
        return next_edge(graph, node_id, ctg), True
    ok = {e.id for e in open_edges(graph, node_id, features)}
    kind = graph.node(node_id).kind
    best, best_cost = None, math.inf
    for e in graph.out_edges(node_id):
        if e.id not in ok or (kind == "nominal" and e.kind == "recovery"):
            continue
        c = e.cost + ctg[e.target]
        if c < best_cost:
            best, best_cost = e, c
    return (best, True) if best is not None else (next_edge(graph, node_id, ctg), False)


class Branch(BaseModel):
    """One recovery route's verdict under Eq. 8."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    edge: str | None
    """The recovery edge that merges into the nominal graph (None: the branch never merges)."""
    context: str
    """Failure context u: the last completed nominal node."""
    via: str | None
    """The recovery node the merge edge leaves (None: straight from the context)."""
    merge: str | None
    monitors: tuple[str, ...]
    """Monitors whose recovery leads along this branch."""
    cost_context: float
    cost_merge: float | None
    """C(merge); None when the goal cannot be reached from it."""
    kept: bool
    reason: str


class FilterResult(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, arbitrary_types_allowed=True)

    graph: TaskGraph
    kept: tuple[Branch, ...]
    rejected: tuple[Branch, ...]
    cost_to_go: dict[str, float]


def _fmt(c: float) -> str:
    return "inf" if math.isinf(c) else f"{c:g}"


def forward_filter(graph: TaskGraph) -> FilterResult:
    """Apply Eq. 8 to every recovery branch; return the pruned graph and each branch's verdict."""
    ctg = cost_to_go(graph)
    kinds = {n.id: n.kind for n in graph.nodes}
    edges = graph.edge_map
    rec_out: dict[str, list[Edge]] = {}
    for e in graph.edges:
        if e.kind == "recovery":
            rec_out.setdefault(e.source, []).append(e)

    # Which monitors lead along which recovery edge, and each recovery node's (unique) context.
    leads: dict[str, set[str]] = {}
    context_of: dict[str, str] = {}
    for e, m in graph.monitors():
        if m.recovery is None:
            continue
        stack, seen = [edges[m.recovery]], set()
        while stack:
            r = stack.pop()
            if r.id in seen:
                continue
            seen.add(r.id)
            leads.setdefault(r.id, set()).add(m.id)
            if kinds[r.target] == "recovery":
                context_of[r.target] = e.source
                stack.extend(rec_out.get(r.target, ()))

    decisions: list[Branch] = []
    drop_edges: set[str] = set()
    for e in graph.edges:
        if e.kind != "recovery" or kinds[e.target] != "nominal":
            continue
        u = e.source if kinds[e.source] == "nominal" else context_of[e.source]
        cu, cm = ctg[u], ctg[e.target]
        if math.isinf(cm):
            kept, reason = False, f"merge node {e.target!r} cannot reach the goal"
        elif cm <= cu + _EPS * max(1.0, cu):
            kept, reason = True, f"C({e.target})={_fmt(cm)} <= C({u})={_fmt(cu)}"
        else:
            kept, reason = False, f"moves backward: C({e.target})={_fmt(cm)} > C({u})={_fmt(cu)}"
        if not kept:
            drop_edges.add(e.id)
        decisions.append(Branch(
            edge=e.id, context=u, via=None if e.source == u else e.source, merge=e.target,
            monitors=tuple(sorted(leads.get(e.id, ()))), cost_context=cu,
            cost_merge=None if math.isinf(cm) else cm, kept=kept, reason=reason,
        ))

    # Recovery nodes that can no longer reach a nominal node through kept recovery edges.
    dead = _dead_recovery_nodes(graph, kinds, drop_edges)
    never = _dead_recovery_nodes(graph, kinds, set())  # could not merge even before pruning
    for r in sorted(never):
        u = context_of[r]
        decisions.append(Branch(
            edge=None, context=u, via=r, merge=None,
            monitors=tuple(sorted(set().union(*(leads.get(x.id, set()) for x in graph.edges if x.target == r)))),
            cost_context=ctg[u], cost_merge=None, kept=False,
            reason=f"recovery node {r!r} never merges back into the nominal graph",
        ))
    for e in graph.edges:
        if e.source in dead or e.target in dead:
            drop_edges.add(e.id)

    pruned = _prune(graph, dead, drop_edges) if (dead or drop_edges) else graph
    return FilterResult(
        graph=pruned,
        kept=tuple(d for d in decisions if d.kept),
        rejected=tuple(d for d in decisions if not d.kept),
        cost_to_go=cost_to_go(pruned),
    )


def _dead_recovery_nodes(graph: TaskGraph, kinds: dict[str, str], dropped: set[str]) -> set[str]:
    """Recovery nodes with no path of recovery edges (other than `dropped`) into a nominal node."""
    alive: set[str] = set()
    preds: dict[str, list[str]] = {}
    frontier = []
    for e in graph.edges:
        if e.kind != "recovery" or e.id in dropped or kinds[e.source] != "recovery":
            continue
        if kinds[e.target] == "nominal":
            frontier.append(e.source)
        else:
            preds.setdefault(e.target, []).append(e.source)
    while frontier:
        r = frontier.pop()
        if r not in alive:
            alive.add(r)
            frontier.extend(preds.get(r, ()))
    return {n for n, k in kinds.items() if k == "recovery" and n not in alive}


def _prune(graph: TaskGraph, dead_nodes: set[str], dead_edges: set[str]) -> TaskGraph:
    edges = []
    for e in graph.edges:
        if e.id in dead_edges:
            continue
        if any(m.recovery in dead_edges for m in e.monitors):
            mons = tuple(m.model_copy(update={"recovery": None}) if m.recovery in dead_edges else m for m in e.monitors)
            e = e.model_copy(update={"monitors": mons})
        edges.append(e)
    return TaskGraph(
        version=graph.version, task=graph.task, start=graph.start, goal=graph.goal,
        nodes=tuple(n for n in graph.nodes if n.id not in dead_nodes), edges=tuple(edges),
    )
