"""Graph augmentation (Eq. 5-7): insert an arranger's recovery proposals into a nominal graph.

A proposal names the nominal edge it anticipates a failure on, the monitor that detects it,
and the recovery nodes and edges that route from the failure context back into the graph
(to an existing nominal node when the recovery intent matches one, Sec. III-C). The result is
checked like any graph; Eq. 8 pruning is `forward.forward_filter`.
"""

from __future__ import annotations

from typing import Annotated, Iterable

from pydantic import Field, ValidationError

from kintsugi.taskgraph.base import GraphError, GraphModel, Id
from kintsugi.taskgraph.model import Edge, Monitor, Node, TaskGraph, describe_validation_error


class RecoveryProposal(GraphModel):
    """One anticipated failure mode on a nominal edge, with its monitor and recovery branch."""

    edge: Id
    """The nominal edge the failure may occur on; its source node is the failure context."""
    monitor: Monitor
    """`monitor.recovery` names the first recovery edge (leaving the failure context)."""
    nodes: Annotated[tuple[Node, ...], Field(max_length=32)] = ()
    """New recovery nodes; leave empty to merge straight into an existing nominal node. A branch that first
    sees how a fallen object lies has one chain per outcome (standing, lying, ...), each up to a full
    re-grasp-and-carry, so a bound of 16 was met by real re-plans."""
    edges: Annotated[tuple[Edge, ...], Field(max_length=48)] = ()


def parse_proposals(data: object) -> list[RecoveryProposal]:
    """Parse a list of proposals (e.g. a reasoner's reply); any problem is one GraphError."""
    if not isinstance(data, list):
        raise GraphError(f"recovery proposals must be a JSON list, got {type(data).__name__}")
    out = []
    for i, item in enumerate(data):
        try:
            out.append(RecoveryProposal.model_validate(item))
        except ValidationError as exc:
            raise GraphError(f"recovery proposal {i} rejected: {describe_validation_error(exc, item)}") from None
        except RecursionError:
            raise GraphError(f"recovery proposal {i} is nested too deeply") from None
    return out


def augment(graph: TaskGraph, proposals: Iterable[RecoveryProposal]) -> TaskGraph:
    """Return a new graph with every proposal's monitor, recovery nodes and recovery edges added.

    The arranger only makes recovery elements, so their `kind` is set to recovery here.
    """
    monitors: dict[str, list[Monitor]] = {e.id: list(e.monitors) for e in graph.edges}
    nodes: list[dict] = []
    edges: list[dict] = []
    for p in proposals:
        target = graph.edge_map.get(p.edge)
        if target is None or target.kind != "nominal":
            raise GraphError(f"recovery proposal for {p.edge!r}: no such nominal edge in the graph")
        monitors[p.edge].append(p.monitor)
        nodes.extend({**n.model_dump(), "kind": "recovery"} for n in p.nodes)
        edges.extend({**e.model_dump(), "kind": "recovery"} for e in p.edges)
    base = [{**e.model_dump(), "monitors": [m.model_dump() for m in monitors[e.id]]} for e in graph.edges]
    # Re-validated from plain data so size limits (monitors per edge, nodes, edges) hold here too.
    return TaskGraph.from_data(
        {"version": graph.version, "task": graph.task, "start": graph.start, "goal": graph.goal,
         "nodes": [n.model_dump() for n in graph.nodes] + nodes, "edges": base + edges}
    )
