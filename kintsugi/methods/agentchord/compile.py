"""Compiling a tabletop task into a recovery-augmented task graph before execution (AgentChord's planning
calls): composer -> nominal graph, arranger -> monitors and recovery branches, Eq. 8 filter. Only the
first observation, the task's declared instruction and goal, and the action library go in."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from pydantic import ValidationError

from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.observe import seen_arms, seen_objects
from kintsugi.methods.agentchord.vocab import tabletop_vocabulary
from kintsugi.reasoning.arranger import ask_arrange
from kintsugi.reasoning.composer import ask_compose
from kintsugi.reasoning.symbolic import PlanningError
from kintsugi.reasoning.taskgraph_types import ArrangerReply, ArrangerRequest, ComposerReply, ComposerRequest
from kintsugi.taskgraph.forward import FilterResult
from kintsugi.reasoning.validation import describe_validation_error
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


def compile_graph(reasoner: Any, spec: Any, observation: Any) -> Compiled:
    """spec: the task's TaskSpec (instruction, goal, objects); observation: the robot's first Observation.
    Raises ReasoningError (recorded in the transcript when the reasoner records) when a role fails."""
    vocab = tabletop_vocabulary(spec.objects)
    objects, arms = seen_objects(observation.objects), seen_arms(observation.arms)
    t0 = time.perf_counter()
    try:
        request = ComposerRequest(task=spec.instruction, goal=list(spec.goal), objects=objects, arms=arms,
                                  domain=TABLETOP_DOMAIN, images_png=dict(observation.images_png))
    except ValidationError as exc:
        raise PlanningError(f"task {spec.name!r} cannot be composed: {describe_validation_error(exc)}") from None
    nominal, composed = ask_compose(reasoner, request, vocab)
    t1 = time.perf_counter()
    arrange = ArrangerRequest(task=spec.instruction, graph=composed.graph, node_facts=composed.node_facts,
                              edge_operators=composed.edge_operators, objects=objects, arms=arms,
                              domain=TABLETOP_DOMAIN, images_png=dict(observation.images_png))
    result, arranged = ask_arrange(reasoner, arrange, nominal, vocab)
    t2 = time.perf_counter()
    return Compiled(nominal, result, composed, arranged, {"composer": t1 - t0, "arranger": t2 - t1})
