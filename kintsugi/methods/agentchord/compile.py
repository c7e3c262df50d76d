"""Compiling a tabletop task into a recovery-augmented task graph before execution (AgentChord's planning
calls): composer -> goal and nominal graph, arranger -> monitors and recovery branches, Eq. 8 filter. Only
the first observation, the task's instruction (the composer reads the goal from it; the task's own goal
predicates are the scorer's ground truth and never go in) and the action library go in."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from pydantic import ValidationError

from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.observe import seen_arms, seen_objects
from kintsugi.methods.agentchord.vocab import tabletop_vocabulary
from kintsugi.methods.agentchord.arranger import ask_arrange
from kintsugi.methods.agentchord.composer import ask_compose
from kintsugi.methods.agentchord.symbolic import PlanningError
from kintsugi.methods.agentchord.types import (ArrangerReply, ArrangerRequest, ComposerReply, ComposerRequest,
                                               SeenObject)
from kintsugi.taskgraph.augment import RecoveryProposal, augment
from kintsugi.taskgraph.forward import FilterResult, forward_filter
from kintsugi.reasoning.jsontext import describe_validation_error
from kintsugi.taskgraph.model import TaskGraph


@dataclass
class Compiled:
    nominal: TaskGraph
    result: FilterResult
    composer: ComposerReply
    arranger: ArrangerReply
    timings_s: dict[str, float] = field(default_factory=dict)

    @property
    def graph(self) -> TaskGraph:
        """The augmented, Eq. 8-filtered graph the conductor runs."""
        return self.result.graph


def task_regions(spec: Any, cfg: Any) -> dict[str, tuple[float, float]]:
    """The task statement's fixed regions (where the green patch is painted; part of the task, like the
    instruction, not simulator state) by name; with exactly one, it is also `target` ("the target region").
    Regions beside an object are not listed: the composer places them from the object's perceived centre."""
    if cfg is None:
        return {}
    fixed = {n: tuple(cfg.targets[n].center_m) for n in getattr(spec, "targets", ())
             if n in cfg.targets and cfg.targets[n].relative_to is None}
    if len(fixed) == 1 and "target" not in fixed:
        fixed["target"] = next(iter(fixed.values()))
    return fixed


def task_region_sizes(spec: Any, cfg: Any, domain: Any) -> dict[str, tuple[float, float]]:
    """The half-extents the task statement gives its regions, by the place the goal names them with: a fixed
    region by its name (and `target` when it is the only one), a region beside an object by the domain's place
    at the same offset from it (`beside_left(plate)` for a region 18 cm left of the plate)."""
    if cfg is None:
        return {}
    out: dict[str, tuple[float, float]] = {}
    for n in getattr(spec, "targets", ()):
        r = cfg.targets.get(n)
        if r is None:
            continue
        half = (float(r.half_m[0]), float(r.half_m[1]))
        if r.relative_to is None:
            out[n] = half
            continue
        for place, offset in domain.relative_places.items():
            if all(abs(float(a) - float(b)) < 1e-6 for a, b in zip(r.center_m, offset)):
                out[f"{place}({r.relative_to})"] = half
    named = [n for n in task_regions(spec, cfg) if n in out]
    if len(named) == 1 and "target" not in out:  # the only fixed region is also "the target region"
        out["target"] = out[named[0]]
    return out


def labelled(objects: list[SeenObject], spec: Any, cfg: Any) -> list[SeenObject]:
    """The perceived objects with the labels the task gives them (kind, colour: what a detector or a model
    looking at the images would name), so the instruction may name them so ("the brown box")."""
    out = []
    for o in objects:
        decl = getattr(spec, "declared", {}).get(o.name) or getattr(getattr(cfg, "objects", None), o.name, None)
        kind, colour = getattr(decl, "kind", None), getattr(decl, "colour", None)
        out.append(o.model_copy(update={"kind": kind, "colour": colour}) if kind or colour else o)
    return out


def compile_graph(reasoner: Any, spec: Any, observation: Any, arranger: bool = True,
                  goal: list[str] | None = None, cfg: Any = None, first: Any = None) -> Compiled:
    """spec: the task's TaskSpec (its instruction and object names are read; its goal is not); `goal`: when
    re-planning, the part of the composed goal still to reach; observation: the robot's first Observation, or
    the current one when re-planning mid-task, with `first` the task's first Observation (what the composer
    remembers of the scene: its static facts, and its images for a model).
    Raises ReasoningError (recorded in the transcript when the reasoner records) when a role fails.
    With `arranger=False` (ReKep-style) there is one planning call: the monitors are the nominal graph's own
    constraints that must persist along each edge (detect-only), no recovery branches."""
    vocab = tabletop_vocabulary(spec.objects)
    objects, arms = labelled(seen_objects(observation.objects), spec, cfg), seen_arms(observation.arms)
    regions, sizes = task_regions(spec, cfg), task_region_sizes(spec, cfg, TABLETOP_DOMAIN)
    t0 = time.perf_counter()
    try:
        request = ComposerRequest(task=spec.instruction, goal=list(goal or []),
                                  objects=objects, arms=arms, regions=regions, region_sizes=sizes,
                                  domain=TABLETOP_DOMAIN, images_png=dict(observation.images_png),
                                  first_objects=seen_objects(first.objects) if first is not None else [],
                                  first_images_png=dict(first.images_png) if first is not None else {})
    except ValidationError as exc:
        raise PlanningError(f"task {spec.name!r} cannot be composed: {describe_validation_error(exc)}") from None
    nominal, composed = ask_compose(reasoner, request, vocab)
    t1 = time.perf_counter()
    if not arranger:
        result = forward_filter(augment(nominal, persistent_monitors(nominal, composed)))
        return Compiled(nominal, result, composed, ArrangerReply(proposals=[], reasoning="no arranger"),
                        {"composer": t1 - t0, "arranger": 0.0})
    arrange = ArrangerRequest(task=spec.instruction, graph=composed.graph, node_facts=composed.node_facts,
                              edge_operators=composed.edge_operators, objects=objects, arms=arms,
                              regions=regions, region_sizes=sizes, goal=list(composed.goal),
                              domain=TABLETOP_DOMAIN, images_png=dict(observation.images_png))
    result, arranged = ask_arrange(reasoner, arrange, nominal, vocab)
    t2 = time.perf_counter()
    return Compiled(nominal, result, composed, arranged, {"composer": t1 - t0, "arranger": t2 - t1})


def persistent_monitors(graph: TaskGraph, composed: ComposerReply) -> list[RecoveryProposal]:
    """Detect-only monitors from the constraints of the facts about a held object that hold at both ends of
    each nominal edge (holding it, keeping it upright or lifted while carrying): ReKep's path constraints,
    compiled once."""
    from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
    from kintsugi.methods.agentchord.composer import node_constraints
    from kintsugi.methods.agentchord.symbolic import parse_literals

    out = []
    for e in graph.edges:
        facts = [set(parse_literals(composed.node_facts.get(n, []), TABLETOP_DOMAIN, where="node facts")[0])
                 for n in (e.source, e.target)]
        kept = facts[0] & facts[1]
        held = {a[2] for a in kept if a[0] == "holding"}
        kept = sorted(a for a in kept if a[0] == "holding" or (a[0] in ("upright", "lifted") and a[1] in held))
        constraints, _ = node_constraints(TABLETOP_DOMAIN, kept, {})
        for i, c in enumerate(constraints):
            margin = PATH_MARGIN_DEG if c["kind"] in ("upright", "tilted") else PATH_MARGIN_M
            out.append(RecoveryProposal.model_validate({
                "edge": e.id, "monitor": {"id": f"p.{e.id}.{i}", "failure_mode": f"path_{c['kind']}", "check": c,
                                          "margin": margin, "window": 3,
                                          "description": "path constraint on a held object (detect only)"}}))
    return out


PATH_MARGIN_M = 0.02
PATH_MARGIN_DEG = 10.0
"""Robustness margins (Eq. 12's epsilon) of the path monitors: perception noise is a few millimetres/degrees."""
