"""The `agentchord` method (system B): compile once (composer, arranger, Eq. 8, keyframes), then conduct
with no reasoning calls at run time.

Its per-trial figures (episode steps, modelled execution time, run-time reasoning calls, recovery latency)
are the record's `method_figures` (`RunFigures`), deterministic so equal seeds give equal records;
`metrics_of(record)` adds the measured execution time (sim time + the record's reasoning latency).
"""

from __future__ import annotations

import time
from typing import Any, Literal

import numpy as np

from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.core.record import Figures
from kintsugi.core.errors import ConfigError, KintsugiError
from kintsugi.core.registry import METHODS
from kintsugi.methods.agentchord.compile import compile_graph
from kintsugi.methods.agentchord.conducting import ConductorConfig
from kintsugi.methods.agentchord.conductor import Conductor
from kintsugi.methods.agentchord.keyframes import KeyframeError, TabletopKeyframes  # noqa: F401
from kintsugi.core.log import TrialLog

class LatencySettings(StrictModel):
    """`--set method.latency_model_s=...`: the stated latency behind the modelled execution time."""

    latency_model_s: float = Field(default=5.0, ge=0)
    """Stated per-call latency of a remote model, for the modelled execution time (not measured)."""


class AgentChordSettings(ConductorConfig, LatencySettings):
    """`--set method.<key>=...` for AgentChord: the conductor's settings and the latency model."""


class BacktrackSettings(AgentChordSettings):
    """AC-BT and ReKep: on a firing, back to the latest nominal sub-goal that still holds."""

    on_failure: Literal["branch", "backtrack"] = "backtrack"


class RunFigures(Figures):
    """An agentchord trial's own figures (`method_figures`): deterministic, so equal seeds give equal records."""

    episode_steps: int
    """Control steps spent in atomic actions (the paper's episode steps)."""
    modelled_execution_time_s: float
    """Sim time + reasoning calls x `latency_model_s` (a stated model of a remote endpoint, not measured)."""
    latency_model_s: float
    planning_reasoning_calls: int
    runtime_reasoning_calls: int
    """Calls after the initial planning (AgentChord: none by design; counted, not assumed)."""
    recovery_latency_steps: list[int]
    """Per recovery: control steps from the monitor's firing to the recovery's first command."""
    recoveries: int
    replans: int = 0
    """Re-plans from the current observation at run time (AgentChord's fallback, at most `max_replans`; a
    re-planning baseline's every re-plan), each recorded as a `replan` event with its reason."""
    actions: int
    graph_nodes: int
    graph_edges: int
    monitors: int


class AgentChordMetrics(RunFigures):
    """The issue's per-trial figures: the event's, plus the measured execution time from the record."""

    execution_time_s: float
    """Sim time + measured reasoning time (every call, planning included)."""


class AgentChord:
    """`arranger=False` compiles monitors from the nominal graph's persistent constraints instead (ReKep-style);
    `config.on_failure="backtrack"` backtracks instead of branching (AC-BT, ReKep-style)."""

    def __init__(self, ctx: Any, config: AgentChordSettings = AgentChordSettings(), arranger: bool = True) -> None:
        self.ctx = ctx
        self.config = config
        self.arranger = arranger

    def run(self, robot: Any, log: TrialLog) -> bool:
        from kintsugi.reasoning import make_reasoner
        from kintsugi.reasoning.base import RecordingReasoner

        reasoner = RecordingReasoner(make_reasoner(self.ctx.reasoner), records=[])
        cfg = self.ctx.cfg
        steps_per_tick = max(1, round(cfg.sim.control_dt_s / cfg.sim.timestep_s))
        try:
            first = robot.observation(images=reasoner.sees_images)
            compiled = compile_graph(reasoner, self.ctx.task, first, arranger=self.arranger, cfg=cfg)
            planning_calls = len(reasoner.records)
            keyframes = TabletopKeyframes(cfg)
            t0 = time.perf_counter()
            try:
                compiled_kf = self._compile_keyframes(compiled, keyframes, first)
            except KeyframeError as exc:  # out of reach before anything moves: a recorded failure, not an error
                log.event(robot.sim_time, "unreachable", f"{exc}; the trial ends as a failure before it moves")
                return False
            compiled.timings_s["keyframes"] = time.perf_counter() - t0
            g = compiled.graph
            log.event(robot.sim_time, "compiled", f"{len(g.nodes)} nodes, {len(g.edges)} edges, "
                      f"{len(g.monitors())} monitors, {len(compiled.result.kept)} recovery branches kept "
                      f"({len(compiled.result.rejected)} dropped by Eq. 8)")
            conductor = Conductor(g, robot, keyframes, log, steps_per_tick, compiled_kf,
                                  ConductorConfig(**self.config.model_dump(include=set(ConductorConfig.model_fields))),
                                  seen=first.objects)
            conductor.replan = self._replanner(reasoner, conductor, robot, first, list(compiled.composer.goal))
            conductor.handover_goals = handed_objects(compiled.composer.goal)
            conductor.tops.observe(first.objects)
            conductor.heads.seed(first.objects)
            try:
                ok = conductor.run()
            finally:
                m = conductor.metrics
                latency = self.config.latency_model_s
                runtime_calls = len(reasoner.records) - planning_calls
                metrics = RunFigures(
                    episode_steps=m.episode_steps,
                    modelled_execution_time_s=round(robot.sim_time + len(reasoner.records) * latency, 4),
                    latency_model_s=latency, planning_reasoning_calls=planning_calls,
                    runtime_reasoning_calls=runtime_calls, recovery_latency_steps=m.recovery_latency_steps,
                    recoveries=m.recoveries, replans=m.replans, actions=m.actions,
                    graph_nodes=len(g.nodes), graph_edges=len(g.edges), monitors=len(g.monitors()))
                log.figures(metrics)
            return ok
        finally:
            log.transcript.extend(r.model_dump(mode="json") for r in reasoner.records)

    def _replanner(self, reasoner: Any, conductor: Conductor, robot: Any, first: Any, read: list[str]) -> Any:
        """The conductor's fallback: compose and arrange again from the current observation (remembering the first
        one's static facts), for the goal the composer read from the instruction (`read`) less the pours already
        seen done; None when the goal already holds."""
        from kintsugi.methods.agentchord.composer import GoalHolds, record_goal_holds

        def replan() -> Any:
            done = {f"poured({o}, {c})" for (o, c), ok in conductor.pours.items() if ok}
            handed = conductor.seen_handovers()
            goal = [g for g in read if g.replace(" ", "") not in {d.replace(" ", "") for d in done}
                    and not handed_objects([g]) & handed]
            obs = robot.observation(images=reasoner.sees_images)
            try:
                compiled = compile_graph(reasoner, self.ctx.task, obs, arranger=self.arranger,
                                         goal=goal if len(goal) < len(read) else None,
                                         cfg=self.ctx.cfg, first=first)
            except GoalHolds:
                record_goal_holds(reasoner.records)
                return None
            conductor.tops.observe(obs.objects)
            return compiled.graph
        return replan

    @staticmethod
    def _compile_keyframes(compiled: Any, keyframes: TabletopKeyframes, first: Any) -> dict:
        """Keyframes of the nominal free moves from the first observation, a held object (by the composer's
        node facts) predicted at the grasp point, where a side grasp closes; an infeasible keyframe fails the
        trial before anything moves, with the solver's message."""
        from kintsugi.methods.agentchord.types import parse_atom

        out = {}
        graph = compiled.graph
        for e in graph.edges:
            if e.kind != "nominal" or len(e.actions) != 1 or e.actions[0].name != "move_to_obj":
                continue
            arm = e.actions[0].args["arm"]
            held = {}
            for text in compiled.composer.node_facts.get(e.source, []):
                positive, name, args = parse_atom(text)
                if positive and name == "holding" and args[0] == arm:
                    held[args[1]] = np.zeros(3)
            kf, _ = keyframes.move_target(e, graph.node(e.target), first.objects, held, first.arms[arm])
            out[e.id] = kf.x
        return out


def metrics_of(record: Any) -> AgentChordMetrics | None:
    """An agentchord-family trial's figures with its measured execution time (None for other methods)."""
    figures = RunFigures.of(record)
    if figures is None:
        return None
    return AgentChordMetrics(**figures.model_dump(),
                             execution_time_s=round(record.sim_time + record.reasoning_latency_s, 4))


def _tabletop(ctx: Any, name: str) -> None:
    from kintsugi.worlds.tabletop.context import TabletopContext

    if not isinstance(ctx, TabletopContext):
        raise ConfigError(f"method {name!r} runs the tabletop tasks (system B) only")


@METHODS.register("agentchord", "AgentChord: composer + arranger compile a recovery-augmented task graph once; "
                  "the conductor runs it with monitors and pre-compiled forward recovery, no run-time reasoning",
                  tags=("system-b",), config=AgentChordSettings)
def make_agentchord(ctx: Any, settings: AgentChordSettings) -> AgentChord:
    _tabletop(ctx, "agentchord")
    return AgentChord(ctx, settings)


@METHODS.register("agentchord-bt", "AgentChord's graph and monitors, but on a firing it backtracks to the latest "
                  "nominal sub-goal that still holds and re-runs the nominal edges (paper's AC-BT ablation)",
                  tags=("system-b",), config=BacktrackSettings)
def make_agentchord_bt(ctx: Any, settings: BacktrackSettings) -> AgentChord:
    _tabletop(ctx, "agentchord-bt")
    return AgentChord(ctx, settings)


@METHODS.register("rekep", "ReKep-style: one planning call, the nominal graph's constraints compiled once as "
                  "path monitors (no anticipated failure modes), backtrack on a violation", tags=("system-b",),
                  config=BacktrackSettings)
def make_rekep(ctx: Any, settings: BacktrackSettings) -> AgentChord:
    _tabletop(ctx, "rekep")
    return AgentChord(ctx, settings, arranger=False)


__all__ = ["AgentChord", "AgentChordMetrics", "KeyframeError", "KintsugiError", "metrics_of"]


def handed_objects(goal: Any) -> frozenset[str]:
    """The objects a goal's `handed_over(obj, giver, taker)` literals hand over."""
    from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
    from kintsugi.methods.agentchord.symbolic import parse_literals

    return frozenset(a[1] for a in parse_literals(list(goal), TABLETOP_DOMAIN)[0] if a[0] == "handed_over")
