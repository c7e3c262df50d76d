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

from dataclasses import dataclass
from typing import Any, Callable

from kintsugi.methods.agentchord.composer import arms_named, instructed_ops, node_constraints, place_table
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.methods.agentchord.symbolic import OpTable, PlanningError, State, ground, parse_literals, plan, plan_each
from kintsugi.methods.agentchord.types import ArrangerReply, ArrangerRequest, SeenObject
from kintsugi.taskgraph.augment import augment, parse_proposals
from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.forward import FilterResult, cost_to_go, forward_filter
from kintsugi.taskgraph.model import TaskGraph

CARRY_ACTIONS = frozenset({"move_by_offset", "move_to_obj", "move_to_target", "rotate_eef", "drive", "place"})
"""Atomic actions during which a held object can be dropped or slip (`place` lets go on purpose: it is watched
only while the hand is still commanded closed)."""
EMPTY_GRIP_M = 0.01
"""Fingers closed to less than this have nothing between them (every graspable object is wider)."""
SLIP_TOL_M = 0.08
"""A held object's centroid farther than this from the grasp point has slipped in the hand."""
MOVED_TOL_M = 0.03
TOPPLE_TOL_DEG = 30.0
RELEASE_COST = 10.0
"""Control steps of a recovery that only opens the hand (the failure already reached the merge node)."""


@dataclass(frozen=True)
class FailureMode:
    """One entry of the knowledge base: when it applies, its monitor, and what it leaves behind."""

    name: str
    actions: frozenset[str]
    """Atomic action types it can happen during."""
    needs: str
    """`held`: an object held in the edge's source state; `target`: the object an action reaches for."""
    check: Callable[[str, str], dict]
    margin: float
    window: int
    after: Callable[[State, str, str], State]
    """Predicted symbolic state after the failure, from the failure context's state."""
    why: str


def _drop(s: State, arm: str, obj: str) -> State:
    """The object fell: the hand is empty (the gripper closes on nothing), the object lies on the table,
    nothing about it being lifted, over or tilted holds; we assume it landed upright (if it toppled, the
    `toppled` monitor of the next grasp sees it)."""
    holders = {a[1] for a in s if a[0] == "holding" and a[2] == obj} | {arm}
    keep = {a for a in s if not (a[0] in ("holding",) and a[1] == arm)
            and not (a[0] == "holding" and a[2] == obj)  # an object two arms carry falls from both
            and not (a[0] in ("lifted", "over", "over_place", "tilted") and a[1] == obj)}
    # A lying object (a fork, a block) lands lying, keeping its heading; anything else we assume upright.
    pose = ("flat", obj) if ("flat", obj) in s and ("upright", obj) not in s else ("upright", obj)
    return frozenset(keep | {("hand_empty", a) for a in holders} | {("on_table", obj), ("released", obj), pose})


LANDED_DEG = 15.0
"""After a fall, an object whose axis is within this of vertical landed standing (the `upright` predicate's
tolerance), else lying (or leaning: it is stood up the same way)."""


def outcomes(mode: FailureMode, s: State, arm: str, obj: str) -> list[tuple[str, State, list[dict]]]:
    """What the failure may leave, each with the guard (over perceived features) that tells it apart at run
    time: an object that stands on a base (`stands`) and falls may land standing or lying on its side."""
    after = mode.after(s, arm, obj)
    if mode.after is not _drop or ("stands", obj) not in s:
        return [("", after, [])]
    lying = frozenset(a for a in after if a != ("upright", obj))
    return [("standing", after, [{"kind": "upright", "object": obj, "tol_deg": LANDED_DEG}]),
            ("lying", lying, [{"kind": "tilted", "object": obj, "min_deg": LANDED_DEG}])]


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


def _unchanged(s: State, arm: str, obj: str) -> State:
    return s


def _toppled(s: State, arm: str, obj: str) -> State:
    return frozenset(a for a in s if a != ("upright", obj))


FAILURES: tuple[FailureMode, ...] = (
    FailureMode("missed_grasp", frozenset({"grasp"}), "target",
                lambda arm, obj: {"kind": "not_grasped", "arm": arm, "min_opening": EMPTY_GRIP_M}, 0.0, 3, _unchanged,
                "the fingers closed on nothing (opening below any object's width): open and grasp again"),
    FailureMode("object_moved", frozenset({"grasp"}), "target",
                lambda arm, obj: {"kind": "drift", "point": {"entity": obj}, "tol": MOVED_TOL_M, "axes": "xy"},
                0.0, 3, _unchanged,
                "the object slid away from where it was seen at the edge start: grasp it where it is now"),
    FailureMode("toppled", frozenset({"grasp"}), "target",
                lambda arm, obj: {"kind": "upright", "object": obj, "tol_deg": TOPPLE_TOL_DEG}, 0.0, 3, _toppled,
                "the object was knocked over: it must be stood up before a side grasp"),
    FailureMode("drop", CARRY_ACTIONS, "held",
                lambda arm, obj: {"kind": "touching", "arm": arm, "object": obj, "expect": True}, 0.0, 3, _drop,
                "the held object fell out of the hand (the finger pads no longer touch it): pick it up and carry on"),
    FailureMode("slip", CARRY_ACTIONS - {"place"}, "held",
                lambda arm, obj: {"kind": "detached", "arm": arm, "object": obj, "tol": SLIP_TOL_M}, 0.01, 5, _drop,
                "the held object slid out of the grasp point: treat as dropped, pick it up and carry on"),
)
"""Failure modes per atomic action type. IK infeasibility is not a feature-level failure: the conductor
reports an unreachable keyframe as a recorded failure with the solver's message."""


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


def arm_calls(edge: Any) -> list[tuple[str, dict]]:
    """(action name, arguments) of the edge's per-arm calls: a dual `drive` counts as its two arm actions (a
    two-arm grasp can miss like a one-arm one)."""
    out = []
    for a in edge.actions:
        out.append((a.name, a.args))
        if a.name == "drive":
            out += [(v["action"], v) for v in a.args.values() if isinstance(v, dict) and isinstance(v.get("action"), str)]
    return out


def _candidates(mode: FailureMode, edge: Any, u: State, v: State | None = None) -> list[tuple[str, str]]:
    calls = arm_calls(edge)
    kinds = {name for name, _ in calls}
    if not kinds & mode.actions:
        return []
    if mode.needs == "held":  # an edge that lets go on purpose (a handover's giver) is not watched for a drop
        held = [(a[1], a[2]) for a in u if a[0] == "holding" and (v is None or a in v or _placed_by(edge, a[1]))]
        if mode.name == "slip":  # two arms hold a wide object by its rims, far from its centroid by design
            held = [(arm, o) for arm, o in held if sum(1 for _, p in held if p == o) == 1]
        return sorted(held)
    out = []
    for name, args in calls:
        if name in mode.actions and isinstance(args.get("arm"), str) and isinstance(args.get("obj"), str):
            if mode.name == "toppled" and ("upright", args["obj"]) not in u:
                continue  # only what stands can topple (a lying fork's axis is horizontal by design)
            if mode.name == "missed_grasp" and ("narrow", args["obj"]) not in u:
                continue  # a wide object is taken by a thin rim: a closed hand is no sign of a miss (the pads,
                # watched as a drop on the next edge, are)
            if (args["arm"], args["obj"]) not in out:
                out.append((args["arm"], args["obj"]))
    return out


def _placed_by(edge: Any, arm: str) -> bool:
    """The edge lets the arm's object go by a `place` (lowered, then released): a drop before the release is a
    failure (watched while the hand is commanded closed, `touching.while_closed`)."""
    return any(a.name == "place" and a.args.get("arm") == arm for a in edge.actions)


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
    arranger's 320). The branches are the same (`tests/test_arranger_merge.py`)."""
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
    from kintsugi.methods.agentchord.composer import edge_actions

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
    _MERGES.clear()
    _NOMINAL.clear()
    try:
        graph = TaskGraph.from_data(request.graph)
    except GraphError as exc:
        raise PlanningError(f"the graph to arrange is unusable: {_short(exc)}") from None
    missing = [n.id for n in graph.nodes if n.id not in request.node_facts]
    if missing:
        raise PlanningError(f"the embedded arranger needs each node's facts (the composer's node_facts); "
                            f"none for {missing[0]!r}")
    seen = {o.name: o for o in request.objects}
    arms = arms_named(request.task, [a.name for a in request.arms])
    names = [o.name for o in request.objects if o.visible]
    places = _places(request, [a.name for a in request.arms], [o.name for o in request.objects])
    where = place_table(places, request.domain, seen, dict(request.regions))
    ops = OpTable(instructed_ops(request.task, request.domain, arms, names, places))  # masks built once, not per search
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
                    proposals.append(_branch(request, graph, edge, mode, arm, obj, u, facts, ops, ctg, seen, where,
                                             releases=("holding", arm, obj) not in v))
                except PlanningError as exc:
                    notes.append(f"{edge.id} {mode.name}({arm}, {obj}): no recovery ({exc})")
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


def ask_arrange(reasoner: Any, request: ArrangerRequest, graph: TaskGraph, vocabulary: Any
                ) -> tuple[FilterResult, ArrangerReply]:
    """The arranger role on any backend (recorded when the reasoner records) -> the Eq. 8-filtered graph,
    checked against the task's vocabulary."""
    from kintsugi.reasoning.roles import ask_role

    out: dict[str, FilterResult] = {}

    def check(reply: ArrangerReply) -> ArrangerReply:
        out["result"] = check_arrangement(reply, graph, vocabulary)
        return reply

    reply = ask_role(reasoner, "arranger", request, ArrangerReply, embedded_arrange, check, system="system_taskgraph")
    return out["result"], reply


__all__ = ["FAILURES", "FailureMode", "ask_arrange", "check_arrangement", "embedded_arrange"]
