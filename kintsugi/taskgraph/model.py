"""The task graph (Eq. 2, 7): sub-goal nodes, transition edges, monitors and recovery branches.

One typed, frozen data model, serialised as JSON and checked on load; networkx underneath
(`TaskGraph.nx`) for every graph computation. Nodes and edges are `nominal` (the composer's
plan) or `recovery` (the arranger's branches, Eq. 5-6). A monitor sits on a nominal edge and
maps its failure mode to a recovery edge that starts at the edge's source node, the failure
context (Eq. 13). Every TaskGraph instance is structurally sound (see `validate.py`); names
are checked against a task's `Vocabulary` with `validate(vocabulary)`.
"""

from __future__ import annotations

import json
from functools import cached_property
from typing import Annotated, Any, Literal

import networkx as nx
from pydantic import Field, JsonValue, ValidationError, field_validator, model_validator

from kintsugi.taskgraph.base import GraphError, GraphModel, Id, Name, NonNeg, Text
from kintsugi.taskgraph.constraints import Constraint
from kintsugi.taskgraph.vocabulary import Vocabulary

Kind = Literal["nominal", "recovery"]
GripperState = Literal["open", "closed"]

MAX_NODES = 1024
"""A re-plan from a disturbed scene (a handover, stand-ups) with a recovery branch on every edge reached 315."""
MAX_EDGES = 4096
MAX_ITEMS = 32
"""Per node/edge: constraints, actions; per edge: monitors (16)."""
MAX_JSON_CHARS = 2_000_000
MAX_ARG_DEPTH = 6


def _depth(v: Any, limit: int) -> int:
    if limit < 0:
        return 1
    if isinstance(v, dict):
        return 1 + max((_depth(x, limit - 1) for x in v.values()), default=0)
    if isinstance(v, list):
        return 1 + max((_depth(x, limit - 1) for x in v), default=0)
    return 0


class ActionCall(GraphModel):
    """One atomic action call, e.g. {"name": "grasp", "args": {"arm": "left", "object": "cup"}}.

    Arguments are plain JSON, checked by the task's Vocabulary (its per-action validator).
    """

    name: Name
    args: dict[Name, JsonValue] = {}

    @field_validator("args")
    @classmethod
    def _shallow(cls, v: dict[str, Any]) -> dict[str, Any]:
        if _depth(v, MAX_ARG_DEPTH) > MAX_ARG_DEPTH:
            raise ValueError(f"arguments nested deeper than {MAX_ARG_DEPTH} levels")
        return v


class Monitor(GraphModel):
    """A compiled failure detector on a nominal edge (Eq. 11-13).

    Fires when `check` exceeds `margin` (epsilon) for `window` (W) consecutive control steps;
    `recovery` is the recovery edge to run at once, or None to only detect (e.g. AC-BT backtracks).
    """

    id: Id
    failure_mode: Name
    check: Constraint
    margin: NonNeg = 0.0
    window: Annotated[int, Field(strict=True, ge=1, le=10_000)] = 3
    recovery: Id | None = None
    description: Text = ""


class Node(GraphModel):
    """A sub-goal: constraints over features that hold on completion, and intended gripper states."""

    id: Id
    description: Text = ""
    constraints: Annotated[tuple[Constraint, ...], Field(max_length=MAX_ITEMS)] = ()
    gripper: dict[Name, GripperState] = {}
    kind: Kind = "nominal"


class Edge(GraphModel):
    """A transition: atomic action calls run in order, path constraints, monitors, physical cost (e.g. steps)."""

    id: Id
    source: Id
    target: Id
    actions: Annotated[tuple[ActionCall, ...], Field(min_length=1, max_length=MAX_ITEMS)]
    path_constraints: Annotated[tuple[Constraint, ...], Field(max_length=MAX_ITEMS)] = ()
    guard: Annotated[tuple[Constraint, ...], Field(max_length=MAX_ITEMS)] = ()
    """Conditions on the features for taking this edge at all: where a failure can leave more than one
    outcome (a dropped bottle standing or lying), the recovery node branches and the conductor takes the
    cheapest edge whose guard holds when it gets there."""
    monitors: Annotated[tuple[Monitor, ...], Field(max_length=16)] = ()
    kind: Kind = "nominal"
    cost: Annotated[float, Field(strict=True, gt=0.0, le=1e9, allow_inf_nan=False)] = 1.0
    description: Text = ""


class TaskGraph(GraphModel):
    """A directed task graph with optional recovery branches; `start` to terminal `goal`."""

    version: Literal[1] = 1
    task: Text = ""
    start: Id
    goal: Id
    nodes: Annotated[tuple[Node, ...], Field(min_length=1, max_length=MAX_NODES)]
    edges: Annotated[tuple[Edge, ...], Field(max_length=MAX_EDGES)] = ()

    @model_validator(mode="after")
    def _structure(self) -> "TaskGraph":
        from kintsugi.taskgraph.validate import check_structure

        check_structure(self)
        return self

    def model_copy(self, *, update: dict[str, Any] | None = None, deep: bool = False) -> "TaskGraph":
        """A checked copy: pydantic's plain copy would skip the structure checks and keep stale caches."""
        fields = {k: getattr(self, k) for k in type(self).model_fields}
        return type(self).model_validate({**fields, **(update or {})})

    # -- lookups -------------------------------------------------------------------------
    @cached_property
    def node_map(self) -> dict[str, Node]:
        return {n.id: n for n in self.nodes}

    @cached_property
    def edge_map(self) -> dict[str, Edge]:
        return {e.id: e for e in self.edges}

    @cached_property
    def nx(self) -> nx.MultiDiGraph:
        """networkx view: node attr `node`, edges keyed by id with attrs `edge` and `weight` (= cost)."""
        g = nx.MultiDiGraph()
        for n in self.nodes:
            g.add_node(n.id, node=n, kind=n.kind)
        for e in self.edges:
            g.add_edge(e.source, e.target, key=e.id, edge=e, weight=e.cost, kind=e.kind)
        return g

    def node(self, node_id: str) -> Node:
        try:
            return self.node_map[node_id]
        except KeyError:
            raise GraphError(f"no node {node_id!r} in the graph") from None

    def edge(self, edge_id: str) -> Edge:
        try:
            return self.edge_map[edge_id]
        except KeyError:
            raise GraphError(f"no edge {edge_id!r} in the graph") from None

    def out_edges(self, node_id: str, kind: Kind | None = None) -> tuple[Edge, ...]:
        return tuple(e for e in self.edges if e.source == node_id and (kind is None or e.kind == kind))

    def monitors(self) -> tuple[tuple[Edge, Monitor], ...]:
        """Every (nominal edge, monitor) pair, in declaration order."""
        return tuple((e, m) for e in self.edges for m in e.monitors)

    # -- checks and JSON -----------------------------------------------------------------
    def validate(self, vocabulary: Vocabulary) -> "TaskGraph":
        """Check every name against the task's vocabulary; raise GraphError naming the first bad one."""
        from kintsugi.taskgraph.validate import check_structure, check_vocabulary

        check_structure(self)
        check_vocabulary(self, vocabulary)
        return self

    def to_json(self, indent: int | None = None) -> str:
        return self.model_dump_json(indent=indent)

    @classmethod
    def from_json(cls, text: str | bytes, vocabulary: Vocabulary | None = None) -> "TaskGraph":
        """Parse and check a graph (e.g. a reasoner's reply); any problem is one GraphError."""
        if not isinstance(text, (str, bytes, bytearray)):
            raise GraphError(f"a task graph must be JSON text, got {type(text).__name__}")
        if len(text) > MAX_JSON_CHARS:
            raise GraphError(f"task graph JSON is {len(text)} characters; the limit is {MAX_JSON_CHARS}")
        try:
            data = json.loads(text)
        except (ValueError, RecursionError) as exc:
            raise GraphError(f"task graph is not valid JSON: {str(exc)[:200]}") from None
        return cls.from_data(data, vocabulary)

    @classmethod
    def from_data(cls, data: Any, vocabulary: Vocabulary | None = None) -> "TaskGraph":
        """Same as from_json for an already-parsed object (e.g. tool-call arguments)."""
        if not isinstance(data, dict):
            raise GraphError(f"a task graph must be a JSON object, got {type(data).__name__}")
        for key, limit in (("nodes", MAX_NODES), ("edges", MAX_EDGES)):  # refuse floods before parsing them
            if isinstance(data.get(key), list) and len(data[key]) > limit:
                raise GraphError(f"task graph has {len(data[key])} {key}; the limit is {limit}")
        try:
            graph = cls.model_validate(data)
        except ValidationError as exc:
            raise GraphError(f"task graph rejected: {describe_validation_error(exc, data)}") from None
        except RecursionError:
            raise GraphError("task graph is nested too deeply") from None
        if vocabulary is not None:
            graph.validate(vocabulary)
        return graph


def _locate(data: Any, loc: tuple) -> str:
    """Render a pydantic error location, naming list items by their id where they have one."""
    parts: list[str] = []
    node = data
    for key in loc:
        if isinstance(key, int):
            item = node[key] if isinstance(node, list) and 0 <= key < len(node) else None
            ident = item.get("id") if isinstance(item, dict) else None
            if isinstance(ident, str) and len(ident) > 40:  # a hostile id must not flood the message
                ident = ident[:37] + "..."
            parts.append(f"[{key}]" + (f" {ident!r}" if isinstance(ident, str) else ""))
            node = item
        else:
            parts.append(("." if parts else "") + str(key))
            node = node.get(key) if isinstance(node, dict) else None
    return "".join(parts) or "(graph)"


def describe_validation_error(exc: ValidationError, data: Any, limit: int = 6) -> str:
    errs = exc.errors()
    text = "; ".join(f"{_locate(data, tuple(e['loc']))}: {e['msg']}" for e in errs[:limit])
    return text + (f" (+{len(errs) - limit} more)" if len(errs) > limit else "")
