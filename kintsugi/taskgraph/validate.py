"""Checks that make a TaskGraph executable: structure (always) and names (against a Vocabulary).

Each check raises one GraphError naming the offending node, edge or monitor and saying what
to change, so a reasoner can be asked to repair its reply. Cost-based pruning of recovery
branches (Eq. 8) is not a validity rule: it lives in `forward.py`.
"""

from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING

import networkx as nx

from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.vocabulary import Vocabulary

if TYPE_CHECKING:
    from kintsugi.taskgraph.model import TaskGraph


def _dupes(ids) -> list[str]:
    return sorted(i for i, n in Counter(ids).items() if n > 1)


def check_structure(g: "TaskGraph") -> None:
    nodes = {n.id: n for n in g.nodes}
    for what, ids in (
        ("node", [n.id for n in g.nodes]),
        ("edge", [e.id for e in g.edges]),
        ("monitor", [m.id for e in g.edges for m in e.monitors]),
    ):
        dup = _dupes(ids)
        if dup:
            raise GraphError(f"duplicated {what} id {dup[0]!r}; every {what} needs its own id")
    for end in ("start", "goal"):
        nid = getattr(g, end)
        if nid not in nodes:
            raise GraphError(f"{end} {nid!r} is not a node; nodes: {', '.join(sorted(nodes))}")
        if nodes[nid].kind != "nominal":
            raise GraphError(f"{end} {nid!r} must be a nominal node, not a recovery node")
    if g.start == g.goal:
        raise GraphError(f"start and goal are the same node {g.start!r}; a task needs at least one transition")

    for n in g.nodes:
        for i, c in enumerate(n.constraints):
            if not c.bound:
                raise GraphError(
                    f"node {n.id!r} constraint {i} ({c.kind}) has no reference point; give `ref` "
                    "(only edge constraints and monitors may latch it at edge start)"
                )

    edges = {e.id: e for e in g.edges}
    for e in g.edges:
        for end in ("source", "target"):
            nid = getattr(e, end)
            if nid not in nodes:
                raise GraphError(f"edge {e.id!r}: {end} {nid!r} is not a node (dangling edge)")
        if e.kind == "nominal":
            for end in ("source", "target"):
                nid = getattr(e, end)
                if nodes[nid].kind != "nominal":
                    raise GraphError(f"nominal edge {e.id!r}: {end} {nid!r} is a recovery node; make the edge a recovery edge")
        elif e.monitors:
            raise GraphError(f"recovery edge {e.id!r} carries monitors; monitors belong on nominal edges")
        for m in e.monitors:
            if m.recovery is None:
                continue
            r = edges.get(m.recovery)
            if r is None:
                raise GraphError(f"monitor {m.id!r} on edge {e.id!r}: recovery edge {m.recovery!r} does not exist")
            if r.kind != "recovery":
                raise GraphError(f"monitor {m.id!r} on edge {e.id!r}: {m.recovery!r} is a nominal edge, not a recovery edge")
            if r.source != e.source:
                raise GraphError(
                    f"monitor {m.id!r} on edge {e.id!r}: recovery edge {r.id!r} starts at {r.source!r}, "
                    f"but the failure context is {e.source!r} (the edge's source node)"
                )

    _check_recovery(g, nodes)
    _check_nominal(g, nodes)


def _check_recovery(g: "TaskGraph", nodes) -> None:
    triggered = {m.recovery for e in g.edges for m in e.monitors if m.recovery is not None}
    rec_nodes = {n.id for n in g.nodes if n.kind == "recovery"}
    inner = nx.DiGraph()
    inner.add_nodes_from(rec_nodes)
    contexts: dict[str, set[str]] = {r: set() for r in rec_nodes}
    for e in g.edges:
        if e.kind != "recovery":
            continue
        if nodes[e.source].kind == "nominal":
            if e.id not in triggered:
                raise GraphError(
                    f"recovery edge {e.id!r} leaves nominal node {e.source!r} but no monitor maps to it; "
                    "set a monitor's `recovery` to it or drop it"
                )
            if e.target in rec_nodes:
                contexts[e.target].add(e.source)
        elif e.target in rec_nodes:
            inner.add_edge(e.source, e.target, id=e.id)
    if not nx.is_directed_acyclic_graph(inner):
        cycle = nx.find_cycle(inner)
        raise GraphError(f"recovery nodes form a cycle ({' -> '.join(u for u, _ in cycle)}); a recovery must end in a nominal node")
    for r in nx.topological_sort(inner):
        for p in inner.predecessors(r):
            contexts[r] |= contexts[p]
    for r in sorted(rec_nodes):
        if not contexts[r]:
            raise GraphError(f"recovery node {r!r} is never entered: no recovery edge from a failure context leads to it")
        if len(contexts[r]) > 1:
            raise GraphError(
                f"recovery node {r!r} is entered from several failure contexts ({', '.join(sorted(contexts[r]))}); "
                "give each context its own recovery node"
            )


def _check_nominal(g: "TaskGraph", nodes) -> None:
    nom = nx.DiGraph()
    nom.add_nodes_from(n for n, v in nodes.items() if v.kind == "nominal")
    nom.add_edges_from((e.source, e.target) for e in g.edges if e.kind == "nominal")
    reach = nx.descendants(nom, g.start) | {g.start}
    if g.goal not in reach:
        raise GraphError(f"no nominal path from start {g.start!r} to goal {g.goal!r}")
    for n in nom.nodes:
        if n not in reach:
            raise GraphError(f"nominal node {n!r} cannot be reached from start {g.start!r}; connect it or drop it")
    back = nx.ancestors(nom, g.goal) | {g.goal}
    stuck = [n for n in nom.nodes if n not in back]
    if stuck:
        sccs = [c for c in nx.strongly_connected_components(nom.subgraph(stuck)) if len(c) > 1 or any(nom.has_edge(n, n) for n in c)]
        if sccs:
            cyc = sorted(sccs[0])
            raise GraphError(f"nominal cycle with no exit through {', '.join(map(repr, cyc))}: none of them leads to goal {g.goal!r}")
        raise GraphError(f"nominal node {sorted(stuck)[0]!r} is a dead end: no nominal path from it to goal {g.goal!r}")


def check_vocabulary(g: "TaskGraph", vocab: Vocabulary) -> None:
    for n in g.nodes:
        for arm in n.gripper:
            if arm not in vocab.arms:
                raise GraphError(f"node {n.id!r}: gripper state for unknown arm {arm!r}; arms: {', '.join(sorted(vocab.arms))}")
        for i, c in enumerate(n.constraints):
            _check_constraint(c, vocab, f"node {n.id!r} constraint {i} ({c.kind})")
    for e in g.edges:
        for i, a in enumerate(e.actions):
            vocab.check_action(a.name, a.args, f"edge {e.id!r} action {i}")
        for i, c in enumerate(e.path_constraints):
            _check_constraint(c, vocab, f"edge {e.id!r} path constraint {i} ({c.kind})")
        for i, c in enumerate(e.guard):
            _check_constraint(c, vocab, f"edge {e.id!r} guard {i} ({c.kind})")
        for m in e.monitors:
            _check_constraint(m.check, vocab, f"edge {e.id!r} monitor {m.id!r} ({m.check.kind})")


def _check_constraint(c, vocab: Vocabulary, where: str) -> None:
    for entity, role, feature in c.refs():
        vocab.check_ref(entity, role, feature, where)
