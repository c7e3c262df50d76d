"""The arranger role (AgentChord Eq. 4-8): a nominal graph -> monitors and forward-moving recovery branches.

`embedded_arrange` uses a failure-mode knowledge base keyed by atomic action type (`FAILURES`): for each
nominal edge, each mode that fits it gives a monitor (a constraint template over the features, > 0 =
violated, with margin and persistence window) and a predicted symbolic state after the failure. From that
state the symbolic planner finds the cheapest way back to the edge's own target node (the merge node), and
that plan becomes the recovery branch: recovery nodes for its intermediate sub-goals, recovery edges for its
steps. A mode with no plan back is left out (and said so in the reply's reasoning). `check_arrangement`
inserts any backend's proposals (`taskgraph.augment`) and applies Eq. 8 (`taskgraph.forward_filter`).
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.agentchord import merging
from kintsugi.methods.agentchord.composer import (edge_actions, instructed_ops, node_constraints, place_table,
                                                  read_instruction)
from kintsugi.methods.agentchord.failures import (  # noqa: F401 - re-exported: the knowledge base
    FAILURES,
    FailureMode,
    _candidates,
    _drop,
    arm_calls,
    outcomes,
)
from kintsugi.methods.agentchord.merging import RELEASE_COST, _merge, _nominal
from kintsugi.methods.agentchord.symbolic import OpTable, PlanningError, State, parse_literals
from kintsugi.methods.agentchord.types import ArrangerReply, ArrangerRequest, SeenObject
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask
from kintsugi.taskgraph.augment import augment, parse_proposals
from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.forward import FilterResult, cost_to_go, forward_filter
from kintsugi.taskgraph.model import MAX_NODES, TaskGraph

LOCATIONS = ("in_region", "inside")
"""Facts that say where an object is to end up: a carry or place is taking it there."""


def landed(request: ArrangerRequest, graph: TaskGraph, edge: Any, mode: FailureMode, arm: str, obj: str, u: State,
           facts: dict[str, State], seen: dict[str, SeenObject], where: Any) -> tuple[str, State, list[dict]] | None:
    """The outcome where a dropped object landed where it was being taken (a fall in a place's last centimetres,
    or at the end of a carry over its region): the facts about it of the first later node that puts it
    somewhere, with their constraints as the guard, read at rest. None when the edge takes the object nowhere
    new, or the goal forbids a drop (`not dropped(obj)`: the instruction asks for it to be set down). A guard
    it cannot decide (NaN: an axis-less cube's uprightness) does not hold, so the re-grasp stays the fallback."""
    import networkx as nx

    if mode.after is not _drop:
        return None
    try:
        if ("dropped", obj) in parse_literals(request.goal, request.domain, where="goal")[1]:
            return None
    except PlanningError:  # a goal it cannot read might forbid the drop
        return None
    hops = nx.single_source_shortest_path_length(_nominal(graph), edge.target)
    for w in sorted(hops, key=hops.__getitem__):
        going = sorted({a for a in facts[w] if a[0] in LOCATIONS and a[1] == obj} - u)
        if not going:
            continue
        if not all(node_constraints(request.domain, [a], seen, where)[0] for a in going):
            return None  # where it is going has no check (`inside`): a guard without it would pass anywhere
        about = sorted(a for a in facts[w] if obj in a[1:] and a[0] not in ("holding", "lifted", "over", "tilted"))
        guard, _ = node_constraints(request.domain, about, seen, where)
        return "landed", mode.after(u, arm, obj) | frozenset(about), guard
    return None


def _places(request: ArrangerRequest, arms: list[str], objects: list[str]) -> list[str]:
    """The places (regions, directions) the composer's node facts name: constants that are no arm or object."""
    from kintsugi.methods.agentchord.types import parse_atom

    out: list[str] = []
    for texts in request.node_facts.values():
        for t in texts:
            for a in parse_atom(t)[2]:
                if a not in arms and a not in objects and a not in out:
                    out.append(a)
    return out


def _facts(texts: list[str], request: ArrangerRequest) -> State:
    pos, _ = parse_literals(texts, request.domain, where="node facts")
    return pos


def _branch(request: ArrangerRequest, graph: TaskGraph, edge: Any, mode: FailureMode, arm: str, obj: str,
            u: State, facts: dict[str, State], ops: list, ctg: dict[str, float],
            seen: dict[str, SeenObject], where: Any = None, releases: bool = False) -> dict:
    """One RecoveryProposal: monitor, recovery nodes and edges from the failure context to the merge node.
    With more than one possible outcome (`outcomes`), a hub node where the object has come to rest branches
    into one guarded chain per outcome. `releases`: the edge opens the hand on purpose (watch up to then)."""
    tag = f"{edge.id}.{mode.name}.{arm}"
    check = mode.check(arm, obj)
    if releases and check.get("kind") == "touching":  # a closed-on-nothing check reads an open hand as fine
        check = {**check, "while_closed": True}
    outs = outcomes(mode, u, arm, obj)
    done = landed(request, graph, edge, mode, arm, obj, u, facts, seen, where)
    outs = outs if done is None else [done, *outs]
    if len(outs) == 1:
        nodes, edges = _chain(request, graph, edge, mode, arm, tag, edge.source, outs[0][1], [], facts, ops, ctg,
                              seen, where)
    else:
        hub = f"r.{tag}.0"
        nodes = [{"id": hub, "description": f"after {mode.name}: {obj} at rest, released"}]
        # The hand stays where it is: the grasp that follows clears its own way in (it rises over what it would
        # sweep through), so a fall costs no trip home.
        edges = [{"id": f"re.{tag}.0", "source": edge.source, "target": hub, "cost": RELEASE_COST,
                  "actions": [{"name": "open_gripper", "args": {"arm": arm}}],
                  "description": f"recovery for {mode.name}: let {obj} come to rest, then see how it lies"}]
        misses = []
        for label, state, guard in outs:
            try:
                n, e = _chain(request, graph, edge, mode, arm, f"{tag}.{label or 'fell'}", hub, state, guard, facts,
                              ops, ctg, seen, where)
            except PlanningError as exc:
                misses.append(f"{label}: {exc}")
                continue
            nodes, edges = nodes + n, edges + e
        if len(edges) == 1:
            raise PlanningError("; ".join(misses))
    monitor = {"id": f"m.{tag}", "failure_mode": mode.name, "check": check, "margin": mode.margin,
               "window": mode.window, "recovery": edges[0]["id"], "description": mode.why}
    return {"edge": edge.id, "monitor": monitor, "nodes": nodes, "edges": edges}


def _chain(request: ArrangerRequest, graph: TaskGraph, edge: Any, mode: FailureMode, arm: str, tag: str,
           source: str, start: State, guard: list, facts: dict[str, State], ops: list, ctg: dict[str, float],
           seen: dict[str, SeenObject], where: Any) -> tuple[list, list]:
    """Recovery nodes and edges from `source` along the plan from `start` to the merge node; the first edge
    carries `guard`. A plan of no steps releases the hand straight into the merge node."""
    merge, steps = _merge(start, edge, graph, facts, ops, ctg)
    if not steps:
        # Every hand the failure emptied opens: an object two arms carried fell from both, and a merge that
        # counts both hands empty must not leave the other still closed on it (coffee-tray seed 0: the tray
        # fell into its region, the left hand opened, the right still held it, and the goal was called met).
        opens = sorted({arm} | {a[1] for a in facts[edge.source] - start if a[0] == "holding"})
        return [], [{"id": f"re.{tag}.1", "source": source, "target": merge, "cost": RELEASE_COST, "guard": guard,
                     "actions": [{"name": "open_gripper", "args": {"arm": a}} for a in opens],
                     "description": f"recovery for {mode.name}: {merge} already holds, release"}]
    nodes, edges = [], []
    prev, state = source, start
    for i, op in enumerate(steps, 1):
        after = op.apply(state)
        last = i == len(steps)
        target = merge if last else f"r.{tag}.{i}"
        if not last:
            constraints, gripper = node_constraints(request.domain, sorted(after - state), seen, where)
            nodes.append({"id": target, "description": f"recovering from {mode.name}: {op.label} done",
                          "constraints": constraints, "gripper": gripper})
        edges.append({"id": f"re.{tag}.{i}", "source": prev, "target": target, "actions": edge_actions(op, seen, where),
                      "cost": op.cost, "guard": guard if i == 1 else [],
                      "description": f"recovery for {mode.name}: {op.label}"})
        prev, state = target, after
    return nodes, edges


def _short(exc: Exception, limit: int = 800) -> str:
    """An error short enough to quote back to a model (hostile replies can make pydantic echo huge values)."""
    text = str(exc)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def embedded_arrange(request: ArrangerRequest) -> ArrangerReply:
    """Monitors and recovery branches for every nominal edge, from the knowledge base and the planner."""
    merging.clear()
    try:
        graph = TaskGraph.from_data(request.graph)
    except GraphError as exc:
        raise PlanningError(f"the graph to arrange is unusable: {_short(exc)}") from None
    missing = [n.id for n in graph.nodes if n.id not in request.node_facts]
    if missing:
        raise PlanningError(f"the embedded arranger needs each node's facts (the composer's node_facts); "
                            f"none for {missing[0]!r}")
    seen = {o.name: o for o in request.objects}
    reading = read_instruction(request)
    arms = reading.arms
    names = [o.name for o in request.objects if o.visible]
    places = _places(request, [a.name for a in request.arms], [o.name for o in request.objects])
    where = place_table(places, request.domain, seen, dict(request.regions), dict(request.region_sizes))
    ops = OpTable(instructed_ops(request.task, request.domain, arms, names, places, reading=reading))  # masks once
    wanted = set(request.failure_modes)
    facts = {n.id: _facts(request.node_facts[n.id], request) for n in graph.nodes}
    ctg = cost_to_go(graph)
    proposals: list[dict] = []
    notes: list[str] = []
    for edge in graph.edges:
        if edge.kind != "nominal":
            continue
        u = facts[edge.source]
        for mode in FAILURES:
            if mode.name not in wanted:
                continue
            v = facts[edge.target]
            for arm, obj in _candidates(mode, edge, u, v):
                try:
                    branch = _branch(request, graph, edge, mode, arm, obj, u, facts, ops, ctg, seen, where,
                                     releases=("holding", arm, obj) not in v)
                    parse_proposals([branch])  # the reply's own schema: a branch it cannot carry is left out
                    proposals.append(branch)
                except (PlanningError, GraphError) as exc:
                    notes.append(f"{edge.id} {mode.name}({arm}, {obj}): no recovery ({_short(exc, 300)})")
    room, kept = MAX_NODES - len(graph.nodes), 0
    for i, p in enumerate(proposals):  # the reply's own bound on the augmented graph: later edges' branches give way
        if kept + len(p["nodes"]) > room:
            notes.append(f"{len(proposals) - i} branches left out: the graph would exceed {MAX_NODES} nodes")
            proposals = proposals[:i]
            break
        kept += len(p["nodes"])
    covered = sorted({p["monitor"]["failure_mode"] for p in proposals})
    why = f"{len(proposals)} branches ({', '.join(covered) or 'none'})" + (f"; {'; '.join(notes)}" if notes else "")
    return ArrangerReply(proposals=proposals, reasoning=why[:4000])


def check_arrangement(reply: ArrangerReply, graph: TaskGraph, vocabulary: Any = None) -> FilterResult:
    """Insert the proposals into the nominal graph, check it (names against the task's vocabulary when
    given), keep only forward-moving branches (Eq. 8). Any problem is a BadReply naming it (an endpoint is
    asked to repair once)."""
    try:
        proposals = parse_proposals(list(reply.proposals))
        augmented = augment(graph, proposals)
        if vocabulary is not None:
            augmented.validate(vocabulary)
        return forward_filter(augmented)
    except GraphError as exc:
        raise BadReply(f"the recovery proposals are unusable: {_short(exc)}") from None


ARRANGER = ROLES.register(Role(name="arranger", request=ArrangerRequest, reply=ArrangerReply,
                               package="kintsugi.methods.agentchord", embedded=embedded_arrange,
                               system="system_taskgraph"))


def ask_arrange(reasoner: Any, request: ArrangerRequest, graph: TaskGraph, vocabulary: Any
                ) -> tuple[FilterResult, ArrangerReply]:
    """The arranger role on any backend (recorded when the reasoner records) -> the Eq. 8-filtered graph,
    checked against the task's vocabulary."""
    out: dict[str, FilterResult] = {}

    def check(reply: ArrangerReply) -> ArrangerReply:
        out["result"] = check_arrangement(reply, graph, vocabulary)
        return reply

    reply = ask(reasoner, "arranger", request, check)
    return out["result"], reply


__all__ = ["ARRANGER", "FAILURES", "FailureMode", "ask_arrange", "check_arrangement", "embedded_arrange"]
