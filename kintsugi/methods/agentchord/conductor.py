"""The conductor: runs a compiled recovery-augmented graph on the tabletop robot, with no reasoning calls.

From the start node it takes the cheapest nominal edge to the goal (`next_edge`), runs its atomic actions
(a `move_to_obj` goes to its keyframe, re-solved with the latest features just before it runs, warm-started
from the compiled one), and evaluates the edge's monitors (Eq. 12) on the features after every atomic action.
When one fires, the pre-compiled recovery edge it maps to (Eq. 13) starts with the very next command: its
chain of recovery edges runs to the merge node, the failed edge's monitors are read once more there (a
recovery that did not hold is run again, up to `max_recoveries`), and nominal execution continues.

The sampling period is one atomic action: `TabletopRobot.execute` runs an action to completion and offers
no per-tick callback to a method, so monitors read the settled state after each action, and a window of W
control steps (shorter than one sample) is met by one violated sample.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import numpy as np
from rich.markup import escape

from kintsugi.config import StrictModel
from kintsugi.errors import KintsugiError
from kintsugi.methods.agentchord.keyframes import KeyframeError, TabletopKeyframes
from kintsugi.methods.agentchord.observe import features
from kintsugi.taskgraph.forward import cost_to_go, next_edge
from kintsugi.taskgraph.model import Edge, TaskGraph
from kintsugi.taskgraph.monitor import Firing, MonitorBank
from kintsugi.trial import SkillLog, TrialLog


SETTLE_M = 0.001
"""Two reads of every watched centroid this close (about 0.1 s apart): the objects are at rest."""
SETTLE_READS = 2
"""Consecutive still pairs required (one pair can alias with a rocking object's period)."""
SETTLE_TRIES = 25


class ConductorError(KintsugiError):
    """The conductor cannot go on (action budget spent, a recovery node with no way back)."""


class ConductorConfig(StrictModel):
    max_actions: int = 80
    """Atomic actions per episode before the conductor gives up (a recovery loop never ends a trial hanging)."""
    max_recoveries: int = 6
    """Recoveries (or backtracks) per episode before the conductor gives up."""
    on_failure: Literal["branch", "backtrack"] = "branch"
    """branch: the pre-compiled forward recovery (AgentChord); backtrack: back to the latest nominal node whose
    sub-goal still holds and re-run the nominal edges from there (AC-BT, ReKep-style)."""


@dataclass
class Metrics:
    episode_steps: int = 0
    """Control steps spent in atomic actions (the paper's episode steps)."""
    actions: int = 0
    recoveries: int = 0
    recovery_latency_steps: list[int] = field(default_factory=list)
    """Per recovery: control steps from the monitor's firing to the recovery's first command."""
    firings: list[str] = field(default_factory=list)
    keyframe_solves: int = 0


def _objects_of(edge: Edge) -> set[str]:
    names: set[str] = set()
    for m in edge.monitors:
        for entity, role, _ in m.check.refs():
            if role != "arm":
                names.add(entity)
    return names


class Conductor:
    def __init__(self, graph: TaskGraph, robot: Any, keyframes: TabletopKeyframes, log: TrialLog,
                 steps_per_tick: int, compiled_keyframes: dict[str, np.ndarray] | None = None,
                 config: ConductorConfig = ConductorConfig(), metrics: Metrics | None = None) -> None:
        self.graph = graph
        self.robot = robot
        self.keyframes = keyframes
        self.log = log
        self.steps_per_tick = steps_per_tick
        self.last = dict(compiled_keyframes or {})
        self.config = config
        self.metrics = metrics if metrics is not None else Metrics()
        self.after_action: Callable[[Edge, int], bool] | None = None
        """Optional check after each atomic action (edge, index) -> failed? (the re-planning baselines' verifier)."""
        self.ctg = cost_to_go(graph)
        self.arms = {a.args.get("arm") for e in graph.edges for a in e.actions if isinstance(a.args.get("arm"), str)}

    # --- running ------------------------------------------------------------------
    def run(self) -> bool:
        """Traverse the graph to its goal; the framework verdict: the goal reached and its constraints hold."""
        g, node = self.graph, self.graph.start
        while node != g.goal:
            edge = next_edge(g, node, self.ctg)
            if edge is None:
                self.log.event(self.robot.sim_time, "stuck", f"no edge from {node!r} leads to the goal")
                return False
            node = edge.target
            firing = self.run_edge(edge, with_monitors=True)
            while firing is not None and self.config.on_failure == "backtrack":
                self.metrics.recoveries += 1
                if self.metrics.recoveries > self.config.max_recoveries:
                    self.log.event(self.robot.sim_time, "gave up", f"{firing.failure_mode} on {edge.id} after "
                                   f"{self.config.max_recoveries} backtracks")
                    return False
                node = self._backtrack(edge, firing)
                firing = None
            while firing is not None:
                if firing.recovery is None:
                    self.log.event(self.robot.sim_time, "unrecovered", f"{firing.failure_mode} on {edge.id}: "
                                   "the graph has no recovery branch for it")
                    return False
                self.metrics.recoveries += 1
                if self.metrics.recoveries > self.config.max_recoveries:
                    self.log.event(self.robot.sim_time, "gave up", f"{firing.failure_mode} on {edge.id} after "
                                   f"{self.config.max_recoveries} recoveries")
                    return False
                node = self._run_recovery(edge, firing)
                # Read the failed edge's monitors again only where they still apply (a merge past its target,
                # e.g. a release straight to the goal, leaves the hand empty on purpose).
                firing = self._recheck(edge) if node == edge.target else None
        return self.goal_holds()

    def run_edge(self, edge: Edge, with_monitors: bool) -> Firing | None:
        self.log.status(f"{edge.kind} {edge.id}")
        bank = None
        objs = _objects_of(edge)
        if with_monitors and edge.monitors:
            # One sample per atomic action: see the module docstring for why W becomes 1.
            once = [m.model_copy(update={"window": 1}) for m in edge.monitors]
            bank = MonitorBank(once, features(self.robot, objs))
        for i, action in enumerate(edge.actions):
            self._execute(edge, action.name, dict(action.args))
            if with_monitors and self.after_action is not None and self.after_action(edge, i):
                return Firing("verifier", "verify_failed", None, float("nan"), i)
            if bank is not None:
                firing = bank.step(features(self.robot, objs))
                if firing is not None:
                    self._fired(edge, firing)
                    return firing
        return None

    def _backtrack(self, failed: Edge, firing: Firing) -> str:
        """The latest nominal node before the failed edge whose constraints hold now (the start always does)."""
        self.metrics.recovery_latency_steps.append(0)
        arms = [e for m in failed.monitors for e, role, _ in m.check.refs() if role == "arm"]
        chain = self._nominal_path()
        upto = chain[: chain.index(failed.source) + 1]
        names = {e for n in upto for c in self.graph.node(n).constraints for e, role, _ in c.refs() if role != "arm"}
        if arms:
            self.wait_still(arms[0], names | _objects_of(failed), failed)
        f = features(self.robot, names)
        for n in reversed(upto):
            if all(not c.evaluate(f) > 0.0 for c in self.graph.node(n).constraints):
                self.log.event(self.robot.sim_time, "backtrack", f"{firing.failure_mode} on {failed.id}: back to {n!r}")
                self.log.transition(failed.id, f"backtrack:{n}")
                return n
        return self.graph.start

    def _nominal_path(self) -> list[str]:
        out, node = [self.graph.start], self.graph.start
        while node != self.graph.goal:
            node = next_edge(self.graph, node, self.ctg).target
            out.append(node)
        return out

    def _recheck(self, edge: Edge) -> Firing | None:
        """After a recovery merged: the failed edge's monitors that need no edge-start reference, read once."""
        bound = [m.model_copy(update={"window": 1}) for m in edge.monitors if m.check.bound]
        if not bound:
            return None
        firing = MonitorBank(bound).step(features(self.robot, _objects_of(edge)))
        if firing is not None:
            self._fired(edge, firing)
        return firing

    def _fired(self, edge: Edge, firing: Firing) -> None:
        t = self.robot.sim_time
        self.metrics.firings.append(f"{edge.id}:{firing.failure_mode}")
        branch = self.config.on_failure == "branch"
        then = f"recovery {firing.recovery or 'none'}" if branch else "backtrack"
        self.log.event(t, "monitor", f"{firing.monitor} ({firing.failure_mode}) fired on {edge.id} with value "
                       f"{firing.value:.3g} -> {then}")
        if branch and firing.recovery is not None:
            self.log.transition(edge.id, firing.recovery)

    def _run_recovery(self, failed: Edge, firing: Firing) -> str:
        """The recovery chain from the failure context to its merge node; returns the merge node."""
        g = self.graph
        edge = g.edge(firing.recovery)
        self.metrics.recovery_latency_steps.append(0)  # the chain's first command is the next one issued
        self._settle(failed, edge)
        while True:
            self.run_edge(edge, with_monitors=False)
            if g.node(edge.target).kind == "nominal":
                return edge.target
            nxt = next_edge(g, edge.target, self.ctg)
            if nxt is None:  # cannot happen on an Eq. 8-filtered graph: every recovery node merges
                raise ConductorError(f"recovery node {edge.target!r} has no way back into the graph")
            edge = nxt

    def _settle(self, failed: Edge, recovery: Edge) -> None:
        """Open the failing arm's gripper and keep it open until the objects its monitors watch have come to
        rest (two reads within SETTLE_M), so the recovery's perception-conditioned actions (a re-grasp) aim
        at where a dropped object lies, not where it was falling."""
        arms = [e for m in failed.monitors for e, role, _ in m.check.refs() if role == "arm"]
        if arms:
            self.wait_still(arms[0], _objects_of(failed), recovery)

    def wait_still(self, arm: str, objs: set[str], edge: Edge) -> bool:
        """True once the objects are at rest; False if they still move after SETTLE_TRIES reads."""
        if not objs:
            return True
        prev, still = None, 0
        for _ in range(SETTLE_TRIES):
            self._execute(edge, "open_gripper", {"arm": arm})
            now = self.robot.features(objs)
            pts = np.array([now[k].centroid for k in sorted(objs) if now[k].centroid is not None])
            moved = prev is None or pts.shape != prev.shape or not np.all(np.linalg.norm(pts - prev, axis=1) < SETTLE_M)
            still = 0 if moved else still + 1
            if still >= SETTLE_READS:
                return True
            prev = pts
        return False

    def _execute(self, edge: Edge, name: str, args: dict) -> None:
        if self.metrics.actions >= self.config.max_actions:
            raise ConductorError(f"{self.config.max_actions} atomic actions spent without reaching the goal")
        call = {"action": name, **args}
        if name == "move_to_obj" and len(edge.actions) == 1:
            call = self._keyframe_call(edge, call)
        result = self.robot.execute(call)
        self.metrics.actions += 1
        self.metrics.episode_steps += result.steps // self.steps_per_tick
        arm = result.arms[0] if result.arms else "right"
        tcp = self.robot.arm_state(arm).tcp_pos
        goal = {k: round(float(v), 4) for k, v in call.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
        self.log.skill(SkillLog(skill=call["action"], goal=goal, terminal={a: round(v * 1000, 2) for a, v in zip("xyz", tcp)},
                                reached=result.reached, recovery=edge.kind == "recovery", message=result.message,
                                sim_time=round(self.robot.sim_time, 4)))
        flag = "reached" if result.reached else ("IK FAILED" if result.ik_failed else "not reached")
        tag = "[magenta]recovery[/magenta] " if edge.kind == "recovery" else ""
        self.log.say(f"[dim]{self.robot.sim_time:6.2f}s[/dim] {tag}{escape(edge.id)}: [bold]{escape(call['action'])}"
                     f"[/bold] -> {flag} ({escape(result.message)})", markup=True)
        if result.ik_failed:
            raise KeyframeError(f"{edge.id} {name}: {result.message}")

    def _keyframe_call(self, edge: Edge, call: dict) -> dict:
        arm = call["arm"]
        state = self.robot.arm_state(arm)
        held_names = [k for k, n in state.touching.items() if n == 2]
        refs = {e for c in self.graph.node(edge.target).constraints for e, role, _ in c.refs() if role != "arm"}
        objs = self.robot.features({call["obj"], *held_names, *refs})
        tcp = np.array(state.tcp_pos)
        held = {k: np.array(objs[k].centroid) - tcp for k in held_names if objs[k].centroid is not None}
        kf, move = self.keyframes.move_target(edge, self.graph.node(edge.target), objs, held, state,
                                              last=self.last.get(edge.id))
        self.last[edge.id] = kf.x
        self.metrics.keyframe_solves += 1
        return move

    def goal_holds(self) -> bool:
        goal = self.graph.node(self.graph.goal)
        names = {e for c in goal.constraints for e, role, _ in c.refs() if role != "arm"}
        idle = [a for a, state in goal.gripper.items() if state == "open"]
        if idle:  # judge the scene once it is at rest (a placed object may still rock)
            last = next(e for e in self.graph.edges if e.target == goal.id and e.kind == "nominal")
            if not self.wait_still(idle[0], names, last):
                self.log.event(self.robot.sim_time, "goal check", f"{', '.join(sorted(names))} still moving after "
                               f"{SETTLE_TRIES} reads; the goal is not reached at rest")
                return False
        f = features(self.robot, names)
        values = [(c.kind, c.evaluate(f)) for c in goal.constraints]
        bad = [k for k, v in values if v > 0.0]
        unknown = [k for k, v in values if v != v]  # NaN: perception could not decide
        if bad or unknown:
            self.log.event(self.robot.sim_time, "goal check", f"goal {goal.id!r}: violated {', '.join(bad) or '-'}; "
                           f"undecided {', '.join(unknown) or '-'}")
        return not bad

