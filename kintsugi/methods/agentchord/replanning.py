"""The re-planning baselines (paper Sec. IV-A): the reasoner is asked again at run time.

- `inner-monologue`: after every sub-goal the verifier is asked whether it holds; if not, re-plan (composer
  on the current observation) and go on with the new graph.
- `doremi`: the verifier is asked after every atomic action (the finest period the robot API allows) whether
  the held objects' path conditions still hold, and at every sub-goal; re-plan on a failure.
- `code-as-monitor`: the arranger's monitors, compiled once and detect-only; the verifier at every sub-goal;
  re-plan on a firing or a failed check.
Execution is the same conductor as AgentChord's (keyframes, settle before re-perceiving), so the methods
differ only in how failures are found and handled. Re-planning sees the current observation and the task's
first one (as a model that planned the task remembers it): the embedded composer plans from the facts it reads
off the current one plus the static facts of the first (a bottle seen standing still stands once it lies);
history it verified is kept (a pour already done is not visible otherwise).
"""

from __future__ import annotations

import functools
from typing import Any, Literal

from kintsugi.core.errors import ConfigError, ReasoningError
from kintsugi.core.registry import METHODS
from kintsugi.methods.agentchord.compile import compile_graph, persistent_monitors
from kintsugi.methods.agentchord.conducting import ConductorConfig, ConductorError, Metrics, firing_arm
from kintsugi.methods.agentchord.conductor import Conductor
from kintsugi.methods.agentchord.keyframes import KeyframeError, TabletopKeyframes
from kintsugi.methods.agentchord.reaching import Unreachable
from kintsugi.methods.agentchord.symbolic import PlanningError
from kintsugi.methods.agentchord.method import LatencySettings, RunFigures
from kintsugi.methods.agentchord.observe import seen_arms, seen_objects
from kintsugi.methods.agentchord.tops import Heads, Tops
from kintsugi.methods.agentchord.composer import GoalHolds, record_goal_holds
from kintsugi.methods.agentchord.types import VerifyRequest
from kintsugi.methods.agentchord.verifier import ask_verify
from kintsugi.taskgraph.model import Edge, TaskGraph
from kintsugi.core.log import TrialLog

Style = Literal["inner-monologue", "doremi", "code-as-monitor"]
MAX_REPLANS = 6


class Replanning:
    def __init__(self, ctx: Any, style: Style, settings: LatencySettings | None = None) -> None:
        self.ctx = ctx
        self.style = style
        self.settings = settings or LatencySettings()

    def run(self, robot: Any, log: TrialLog) -> bool:
        from kintsugi.reasoning import make_reasoner
        from kintsugi.reasoning.base import RecordingReasoner

        self.robot, self.log = robot, log
        self.goal: list[str] = []
        """The goal the first composition read from the instruction (the task's own goal is the scorer's)."""
        self.done: set[str] = set()
        """Goal facts about history (no constraint can observe them later, e.g. poured) already achieved at a
        verified sub-goal: a re-plan keeps them (the reasoner remembers what it did), the rest is re-observed."""
        self.reasoner = RecordingReasoner(make_reasoner(self.ctx.reasoner), records=[])
        cfg = self.ctx.cfg
        self.images = self.reasoner.sees_images
        steps_per_tick = max(1, round(cfg.sim.control_dt_s / cfg.sim.timestep_s))
        keyframes = TabletopKeyframes(cfg)
        metrics = Metrics()
        self.tops, self.heads = Tops(), Heads()
        """The robot's own memory of which end of each object is its top and which way a utensil's head points
        (encoders while held, continuity while it falls), kept across re-plans as AgentChord keeps it for the
        whole trial: execution is the same, only how failures are found and handled differs."""
        planning_calls = 0
        try:
            ok = False
            for attempt in range(MAX_REPLANS + 1):
                try:
                    graph, composed = self._plan(first=attempt == 0)
                except GoalHolds:
                    if attempt == 0:
                        raise
                    record_goal_holds(self.reasoner.records)
                    log.event(robot.sim_time, "replan", "the composer finds the goal already holds")
                    ok = True
                    break
                except ReasoningError as exc:  # a refused plan, a model's reply unusable after its repair round
                    if attempt == 0:
                        raise
                    refused = isinstance(exc, PlanningError)
                    log.event(robot.sim_time, "replan refused" if refused else "replan failed",
                              f"{'' if refused else type(exc).__name__ + ': '}{exc}; the trial ends as a failure")
                    break
                self.node_facts = composed.node_facts
                if attempt == 0:
                    planning_calls = len(self.reasoner.records)
                self.paths: dict[str, list] = {}
                for proposal in persistent_monitors(graph, composed):
                    self.paths.setdefault(proposal.edge, []).append(proposal)
                conductor = Conductor(graph, robot, keyframes, log, steps_per_tick,
                                      config=ConductorConfig(on_failure="backtrack", max_recoveries=0),
                                      metrics=metrics, tops=self.tops, heads=self.heads, seen=self.seen)
                conductor.after_action = self._after_action(graph) if self.style == "doremi" else None
                try:
                    ok, failed = self._conduct(conductor, graph)
                except (KeyframeError, ConductorError, PlanningError) as exc:  # a spent budget, a lost object
                    log.event(robot.sim_time, "failed", f"{exc}; the trial ends as a failure")
                    ok = False
                    break
                if not failed:
                    break
                metrics.recoveries += 1
                log.event(robot.sim_time, "replan", f"{self.style}: {failed}; asking the composer again")
            return ok
        finally:
            runtime = len(self.reasoner.records) - planning_calls
            latency = self.settings.latency_model_s
            figures = RunFigures(
                episode_steps=metrics.episode_steps,
                modelled_execution_time_s=round(robot.sim_time + len(self.reasoner.records) * latency, 4),
                latency_model_s=latency, planning_reasoning_calls=planning_calls,
                runtime_reasoning_calls=runtime, recovery_latency_steps=metrics.recovery_latency_steps,
                recoveries=metrics.recoveries, replans=metrics.recoveries, actions=metrics.actions, graph_nodes=0,
                graph_edges=0, monitors=0)
            log.figures(figures)
            log.transcript.extend(r.model_dump(mode="json") for r in self.reasoner.records)

    def _plan(self, first: bool) -> tuple[TaskGraph, Any]:
        """A re-plan sees the current observation and remembers the first (a model that planned the task saw
        it): its static facts, e.g. that a bottle now lying stands, so standing it up is a plan."""
        obs = self.robot.observation(images=self.images)
        self.seen = obs.objects
        if first:
            self.first_obs = obs
            self.tops.observe(obs.objects)
            self.heads.seed(obs.objects)
        goal = [g for g in self.goal if g not in self.done] or None
        compiled = compile_graph(self.reasoner, self.ctx.task, obs, arranger=self.style == "code-as-monitor",
                                 goal=goal, cfg=self.ctx.cfg, first=None if first else self.first_obs)
        if not self.goal:
            self.goal = list(compiled.composer.goal)
        graph = compiled.graph
        if self.style == "code-as-monitor":  # detect only: the reasoner is asked again instead of a branch
            graph = TaskGraph.from_data({**graph.model_dump(), "nodes": [n.model_dump() for n in graph.nodes
                                                                         if n.kind == "nominal"],
                                         "edges": [{**e.model_dump(), "monitors": [
                                             {**m.model_dump(), "recovery": None} for m in e.monitors]}
                                             for e in graph.edges if e.kind == "nominal"]})
        else:
            graph = compiled.nominal
        return graph, compiled.composer

    def _conduct(self, conductor: Conductor, graph: TaskGraph) -> tuple[bool, str | None]:
        """Run the graph edge by edge with the style's checks; (verdict, why it must re-plan or None)."""
        from kintsugi.taskgraph.forward import next_edge

        node = graph.start
        while node != graph.goal:
            edge = next_edge(graph, node, conductor.ctg)
            try:
                firing = conductor.run_edge(edge, with_monitors=True)
            except Unreachable as exc:  # a failed action (nothing moved): re-plan from what the cameras see now
                self.log.event(self.robot.sim_time, "unreachable", str(exc))
                return False, f"unreachable action on {edge.id}"
            if firing is not None:
                self._settle(conductor, edge, firing_arm(edge, firing))
                return False, f"{firing.failure_mode} on {edge.id}"
            node = edge.target
            if not self._verify(graph, node):
                self._settle(conductor, edge)
                return False, f"sub-goal {node!r} not verified"
            self._remember(node)
        return conductor.goal_holds(), None

    def _settle(self, conductor: Conductor, edge: Edge, arm: str | None = None) -> None:
        """Let a dropped object come to rest before the next observation is planned from (as AgentChord does).
        Recovery latency runs from the detection to the re-planned graph's first command, so it includes this."""
        m = conductor.metrics
        fired_at, m.fired_at = (m.fired_at if m.fired_at is not None else conductor.robot_steps()), None
        if arm is None:  # the fired monitor's arm; else the edge's first (the other may hold its own object)
            arm = next((a.args["arm"] for a in edge.actions if isinstance(a.args.get("arm"), str)), None)
        if arm is not None:
            conductor.wait_still(arm, set(self.ctx.task.objects), edge)
        m.fired_at = fired_at

    def _remember(self, node: str) -> None:
        from kintsugi.methods.agentchord.types import parse_atom

        lasting = _lasting_unseen()
        facts = set(self.node_facts.get(node, []))
        for g in self.goal:
            positive, name, args = parse_atom(g)
            if positive and name in lasting and f"{name}({', '.join(args)})" in facts:
                self.done.add(g)

    def _verify(self, graph: TaskGraph, node_id: str) -> bool:
        node = graph.node(node_id)
        return self._ask(node.description or node.id, list(node.constraints))

    def _after_action(self, graph: TaskGraph):  # noqa: ANN202 - the conductor's hook
        def check(edge: Edge, i: int) -> bool:
            monitors = self.paths.get(edge.id, [])
            return not self._ask(f"still holding as intended during {edge.description or edge.id}",
                                 [p.monitor.check for p in monitors])
        return check

    def _ask(self, subgoal: str, constraints: list) -> bool:
        if not constraints:
            return True  # nothing to check: no call
        names = {e for c in constraints for e, role, _ in c.refs() if role != "arm"}
        obs_objects = self.robot.features(names or None)
        arms = {a: self.robot.arm_state(a) for a in ("left", "right")}
        request = VerifyRequest(task=self.ctx.task.instruction, subgoal=subgoal,
                                constraints=[c.model_dump(mode="json") for c in constraints],
                                objects=seen_objects(obs_objects), arms=seen_arms(arms),
                                images_png=self.robot.observation(images=True).images_png if self.images else {})
        return ask_verify(self.reasoner, request).success


def _factory(style: Style):  # noqa: ANN202
    def make(ctx: Any, settings: LatencySettings | None = None) -> Replanning:
        from kintsugi.worlds.tabletop.context import TabletopContext

        if not isinstance(ctx, TabletopContext):
            raise ConfigError(f"method {style!r} runs the tabletop tasks (system B) only")
        return Replanning(ctx, style, settings)
    return make


METHODS.register("inner-monologue", "the reasoner verifies every sub-goal and re-plans (composer) on a failure; "
                 "no compiled monitors", tags=("system-b",), config=LatencySettings)(_factory("inner-monologue"))
METHODS.register("doremi", "the reasoner verifies the held objects' conditions after every atomic action and "
                 "every sub-goal, re-plans on a failure", tags=("system-b",), config=LatencySettings)(_factory("doremi"))
METHODS.register("code-as-monitor", "the arranger's monitors compiled once (detect only); the reasoner verifies "
                 "every sub-goal and re-plans on a firing or a failed check", tags=("system-b",),
                 config=LatencySettings)(_factory("code-as-monitor"))


@functools.cache
def _lasting_unseen() -> frozenset[str]:
    """Predicates no constraint checks and no operator undoes (poured): once a verified node had them, they stay
    done across re-plans. `released` is undone by a grasp: remembered because it held at the start, it was left
    out of the goal of a re-plan after the tray fell from both hands, and the plan ended with both hands still
    on the tray (DoReMi and code-as-monitor, coffee-tray seed 0)."""
    from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
    from kintsugi.methods.agentchord.types import parse_atom

    undone = {parse_atom(d)[1] for op in TABLETOP_DOMAIN.operators for d in op.delete}
    return frozenset(p.name for p in TABLETOP_DOMAIN.predicates if not p.constraints and p.name not in undone)
