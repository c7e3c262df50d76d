"""The composer role (AgentChord Eq. 2): instruction + first observation -> nominal task graph.

`embedded_compose` plans, it does not follow a per-task script: it reads the goal from the instruction in
the controlled language (`reading.py`, docs/agentchord-language.md; outside it, it refuses with what it did
not understand), the observed state as facts (what perception and the arms' sensors report), grounds the domain's
operators over the scene and searches for the cheapest plan (`symbolic.plan`). Each step becomes an edge
(its atomic actions, cost in control steps) into a sub-goal node whose constraints check the facts the step
made true. `ask_compose` runs the role on any backend and checks the reply into a `TaskGraph`.
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.agentchord.facts import (  # noqa: F401 - re-exported: the composer's reading of the scene
    looks_upright,
    observed_facts,
    place_table,
    remembered_facts,
    goal_places,
)
from kintsugi.methods.agentchord.instruction import (  # noqa: F401 - re-exported
    arm_bindings, arms_named, held_up, instructed_ops, reading_of, scene_of)
from kintsugi.methods.agentchord.language import NotUnderstood
from kintsugi.methods.agentchord.symbolic import Atom, GroundOp, PlanningError, State, atom_text, parse_literals, plan
from kintsugi.methods.agentchord.templates import edge_actions, fill, node_constraints  # noqa: F401
from kintsugi.methods.agentchord.types import ComposerReply, ComposerRequest, Domain, SeenObject
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask
from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.model import TaskGraph
from kintsugi.taskgraph.vocabulary import Vocabulary

PACKAGE = "kintsugi.methods.agentchord"


class GoalHolds(PlanningError):
    """Planning found nothing to do: the observed scene already satisfies the goal."""


def record_goal_holds(records: list) -> None:
    """A re-plan that found the goal already holding is an answer, not a reasoner error: its transcript record
    (the last one, which the composer's GoalHolds marked failed) keeps the finding as its reply instead."""
    if records and (records[-1].error or "").startswith(f"{GoalHolds.__name__}:"):
        finding = records[-1].error.split(":", 1)[1].strip()
        records[-1] = records[-1].model_copy(update={"error": None, "reply": {"goal_holds": finding}})


def build_graph(task: str, domain: Domain, initial: State, steps: list[GroundOp],
                seen: dict[str, SeenObject], goal: frozenset[Atom] = frozenset(), where: Any = None) -> ComposerReply:
    """A chain graph start -> s1 -> ... -> goal from a plan, with the symbolic state of every node. The goal
    node checks every goal fact (not only the last step's), so the verdict covers the whole task."""
    if not steps:
        raise GoalHolds("the goal already holds in the observed scene; there is nothing to do")
    nodes = [{"id": "start", "description": "the observed scene"}]
    edges = []
    facts = {"start": sorted(atom_text(a) for a in initial)}
    operators = {}
    state, prev = initial, "start"
    for i, op in enumerate(steps, 1):
        after = op.apply(state)
        made = sorted(after - state)
        if i == len(steps):
            made = sorted(set(made) | set(goal))
        constraints, gripper = node_constraints(domain, made, seen, where)
        nid, eid = f"s{i}_{op.name}", f"e{i}_{op.name}"
        nodes.append({"id": nid, "description": ", ".join(atom_text(a) for a in made) or op.label,
                      "constraints": constraints, "gripper": gripper})
        edges.append({"id": eid, "source": prev, "target": nid, "actions": edge_actions(op, seen, where),
                      "cost": op.cost, "description": op.label})
        facts[nid] = sorted(atom_text(a) for a in after)
        operators[eid] = op.label
        state, prev = after, nid
    graph = {"task": task, "start": "start", "goal": prev, "nodes": nodes, "edges": edges}
    why = "plan: " + " -> ".join(op.label for op in steps)
    return ComposerReply(graph=graph, node_facts=facts, edge_operators=operators, reasoning=why)


def _short(exc: Exception, limit: int = 800) -> str:
    """An error short enough to quote back to a model (hostile replies can make pydantic echo huge values)."""
    text = str(exc)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def read_instruction(request: Any):  # noqa: ANN201 - a Reading
    """The request's instruction in the controlled language, over the scene as perceived (the composer's and
    the arranger's request alike); NotUnderstood outside the language."""
    scene = scene_of(request.objects, [a.name for a in request.arms], request.regions, request.domain,
                     getattr(request, "first_objects", ()))
    words = {p.name for p in request.domain.predicates} | set(getattr(request.domain, "aliases", {}))
    return reading_of(request.task, scene, frozenset(words))


def embedded_compose(request: ComposerRequest) -> ComposerReply:
    """Read the goal from the instruction (or take the one still to reach, when re-planning), then plan the
    nominal graph from it and the observed facts (no task script)."""
    domain = request.domain
    seen = {o.name: o for o in request.objects}
    reading = read_instruction(request)
    goal_text = list(request.goal) or reading.goal
    names = [o.name for o in request.objects if o.visible]
    places = goal_places(goal_text, [a.name for a in request.arms], [o.name for o in request.objects])
    where = place_table(places, domain, seen, dict(request.regions), dict(request.region_sizes))
    initial = observed_facts(request, domain, places) | remembered_facts(request, domain)
    goal = parse_literals(goal_text, domain, where="goal")
    ops = instructed_ops(request.task, domain, reading.arms, names, places, reading=reading)
    steps = plan(initial, goal, ops)
    reply = build_graph(request.task, domain, initial, steps, seen, goal[0], where)
    return reply.model_copy(update={"goal": goal_text})


def check_goal(reply: ComposerReply, request: ComposerRequest) -> None:
    """The reply's goal is literals over the domain's predicates naming the scene's objects, arms, regions and
    the domain's places; BadReply names the first that is not."""
    if not reply.goal:
        raise BadReply("the reply has no `goal`: write the instruction's goal as literals over the domain's "
                       "predicates, e.g. [\"inside(ball, bowl)\", \"released(ball)\"]")
    try:
        parse_literals(list(reply.goal), request.domain, where="goal")
    except PlanningError as exc:
        raise BadReply(_short(exc)) from None
    from kintsugi.methods.agentchord.types import parse_atom

    known = ({o.name for o in request.objects} | {a.name for a in request.arms} | set(request.regions)
             | set(request.domain.directions))
    for text in reply.goal:
        for arg in parse_atom(text)[2]:
            fn = arg.split("(")[0]
            inner = arg[len(fn) + 1:-1] if "(" in arg else None
            if inner is not None and (fn not in request.domain.relative_places or inner not in known):
                raise BadReply(f"goal literal {text!r}: {arg!r} is not a place of the domain "
                               f"({', '.join(f'{p}(object)' for p in request.domain.relative_places)})")
            if inner is None and arg not in known:
                raise BadReply(f"goal literal {text!r} names {arg!r}, which is no object, arm, region or direction "
                               "of the request")


def check_composition(reply: ComposerReply, vocabulary: Vocabulary) -> TaskGraph:
    """The reply's graph, parsed and checked against the task's vocabulary; BadReply names what is wrong
    (so an endpoint gets one repair round)."""
    try:
        graph = TaskGraph.from_data(reply.graph, vocabulary)
    except GraphError as exc:
        raise BadReply(f"the task graph is unusable: {_short(exc)}") from None
    stray = [k for k in (*reply.node_facts, *reply.edge_operators) if k not in graph.node_map and k not in graph.edge_map]
    if stray:
        raise BadReply(f"node_facts/edge_operators name {stray[0]!r}, which is not a node or edge of the graph")
    nominal = [n for n in graph.nodes if n.kind != "nominal"] + [e for e in graph.edges if e.kind != "nominal"]
    if nominal:
        raise BadReply(f"the composer's graph must be nominal; {nominal[0].id!r} is a recovery element "
                       "(recovery branches are the arranger's job)")
    return graph


COMPOSER = ROLES.register(Role(name="composer", request=ComposerRequest, reply=ComposerReply, package=PACKAGE,
                               embedded=embedded_compose, system="system_taskgraph"))


def ask_compose(reasoner: Any, request: ComposerRequest, vocabulary: Vocabulary) -> tuple[TaskGraph, ComposerReply]:
    """The composer role on any backend (recorded when the reasoner records) -> a checked nominal graph and the
    goal it read from the instruction (the goal given, when re-planning)."""
    out: dict[str, TaskGraph] = {}

    def check(reply: ComposerReply) -> ComposerReply:
        if request.goal:
            reply = reply.model_copy(update={"goal": list(request.goal)})
        out["graph"] = check_composition(reply, vocabulary)
        check_goal(reply, request)
        return reply

    reply = ask(reasoner, "composer", request, check)
    return out["graph"], reply


__all__ = ["COMPOSER", "GoalHolds", "NotUnderstood", "record_goal_holds", "ask_compose", "check_composition", "check_goal",
           "embedded_compose", "observed_facts", "read_instruction", "PlanningError"]
