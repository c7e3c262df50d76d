"""The conductor: runs a compiled recovery-augmented graph on the tabletop robot, with no reasoning calls.

From the start node it takes the cheapest nominal edge to the goal (`next_edge`), runs its atomic actions (a
`move_to_obj` goes to its keyframe, re-solved from the latest features as it runs) and its monitors (Eq. 12).

Two sampling rates, by what a monitor reads:
- proprioceptive monitors (gripper opening, finger-pad touch: a drop, a missed grasp) are evaluated every
  control step through the robot's per-step observer hook, on `GripSense` (encoders and pads, no images),
  with their persistence window W in control steps; a firing interrupts the running action in that control
  step and the pre-compiled recovery edge it maps to (Eq. 13) issues the next command;
- monitors over perceived object features (drift, upright, slip by centroid) are evaluated on full
  perception after every atomic action (a sub-goal sample; one violated sample meets their window), since a
  render per control step would cost far more than the step itself.
A recovery's chain runs to its merge node; the failed edge's monitors are read once more there (a recovery
that did not hold is run again; after MERGE_FAILS such failures on one edge the conductor falls back to re-planning
from the current observation, at most `max_replans` times), and nominal execution continues. An action the arm
cannot carry out is tried other ways (`Reaching`; an object out of every grasp is pushed back into reach,
`Pushing`), else the trial ends as a recorded failure; a pour sub-goal is judged from perception (`Pouring`).
Recovery latency is counted in control steps from the firing to the recovery's first command (`Metrics`).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
from rich.markup import escape

from kintsugi.core.errors import ReasoningError
from kintsugi.core.log import TrialLog
from kintsugi.core.record import SkillLog
from kintsugi.methods.agentchord.conducting import (ConductorConfig, ConductorError, Interrupted, Metrics, objects_of,
                                                    proprioceptive, strict)
from kintsugi.methods.agentchord.handing import Handing
from kintsugi.methods.agentchord.keyframes import KeyframeError, TabletopKeyframes
from kintsugi.methods.agentchord.observe import ARMS, features
from kintsugi.methods.agentchord.pouring import Pouring
from kintsugi.methods.agentchord.pushing import Pushing
from kintsugi.methods.agentchord.reaching import Reaching, Unreachable
from kintsugi.methods.agentchord.recovering import Recovering
from kintsugi.methods.agentchord.settling import SETTLE_TRIES, Settling
from kintsugi.methods.agentchord.symbolic import PlanningError
from kintsugi.methods.agentchord.synthesis import EdgeSynthesis
from kintsugi.methods.agentchord.tops import Heads, Tops
from kintsugi.perception.features import ObjectFeatures
from kintsugi.taskgraph.features import Features
from kintsugi.taskgraph.forward import cost_to_go, next_edge
from kintsugi.taskgraph.model import Edge, TaskGraph
from kintsugi.taskgraph.monitor import Firing, MonitorBank


MERGE_FAILS = 2
"""A recovery whose merge check fails this many times on one edge falls back to re-planning, as does one run
MAX_RERUNS times (each run disturbed again: a grasp closing on nothing, a loss)."""
MAX_RERUNS = 4
REPLANNED = object()


class Conductor(Recovering, Settling, Reaching, Pushing, Pouring, Handing):
    """Runs one compiled graph to its goal: nominal edges under their monitors, recoveries (`Recovering`) after
    a firing, settles (`Settling`) before a recovery or the goal check reads the scene."""

    def __init__(self, graph: TaskGraph, robot: Any, keyframes: TabletopKeyframes, log: TrialLog,
                 steps_per_tick: int, compiled_keyframes: dict[str, np.ndarray] | None = None,
                 config: ConductorConfig = ConductorConfig(), metrics: Metrics | None = None,
                 tops: Tops | None = None, heads: Heads | None = None,
                 seen: dict[str, ObjectFeatures] | None = None) -> None:
        """`seen`: the objects of the observation the graph's action arguments were filled from (a place back
        where an object was first seen is re-aimed against it)."""
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
        self.synthesis = EdgeSynthesis(graph, robot, keyframes, tops if tops is not None else Tops(),
                                       heads if heads is not None else Heads(),
                                       {k: (f.centroid[0], f.centroid[1]) for k, f in (seen or {}).items()
                                        if f.centroid is not None})
        self.tops, self.heads = self.synthesis.tops, self.synthesis.heads
        self.arms = {a.args.get("arm") for e in graph.edges for a in e.actions if isinstance(a.args.get("arm"), str)}
        self.goal_objects = {e for c in graph.node(graph.goal).constraints for e, role, _ in c.refs() if role != "arm"}
        """The objects the goal check reads: a settle waits for them too (the dropped object may have knocked one),
        so a recovery that merges straight into the goal need not wait again."""
        self.replan: Callable[[], TaskGraph | None] | None = None
        """The fallback when a recovery keeps failing its merge check: a graph compiled from the current
        observation (None: the goal already holds), set by the method."""
        self.merge_failed = False
        self.pours: dict[tuple[str, str], bool] = {}
        """(object, container) of every pour sub-goal reached -> seen done (`Pouring`)."""
        self._rested: tuple[int, frozenset[str]] | None = None
        """(control step, objects) of the last read that found those objects at rest."""

    # --- running ------------------------------------------------------------------
    def run(self) -> bool:
        """Traverse the graph to its goal; the framework verdict: the goal reached and its constraints hold.
        An action no arm can carry out (out of reach, its object out of the cameras' view) or a spent budget
        ends the trial as a recorded failure with the reason, never a trial error."""
        try:
            while True:
                try:
                    outcome = self._traverse()
                except Unreachable as exc:  # re-planned from where things are now, the other arm may reach
                    if not self._may_replan():
                        raise
                    self.log.event(self.robot.sim_time, "unreachable", str(exc))
                    outcome = self._replan(f"{exc.args[0].split(':')[0]} is out of reach")
                if outcome is not REPLANNED:
                    return bool(outcome)
        except (KeyframeError, ConductorError) as exc:
            kind = "unreachable" if isinstance(exc, Unreachable) else "failed"
            self.log.event(self.robot.sim_time, kind, f"{exc}; the trial ends as a failure")
            return False

    def _traverse(self) -> Any:
        """One traversal of the current graph: the verdict, or REPLANNED when it fell back to a new graph."""
        g, node = self.graph, self.graph.start
        merge_fails = reruns = 0
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
                self.merge_failed = False
                node = self._run_recovery(edge, firing)
                if node is not None:
                    # Read the failed edge's monitors again only where they still apply (a merge past its target,
                    # e.g. a release straight to the goal, leaves the hand empty on purpose).
                    firing = self._recheck(edge) if node == edge.target else None
                    self.merge_failed = firing is not None
                merge_fails += self.merge_failed
                reruns += node is None
                if merge_fails >= MERGE_FAILS or reruns >= MAX_RERUNS:  # the branch does not hold: the fallback
                    return self.fall_back(edge, f"its merge check failed {merge_fails} times" if merge_fails
                                          >= MERGE_FAILS else f"it was run {reruns} times")
                # else a recovery that was itself disturbed (a drop, a missed grasp) runs again
        if self.goal_holds():
            return True
        if not self._may_replan():
            return False
        return self._replan("the goal check failed at the end of the graph")  # e.g. a stand-up set it elsewhere

    def fall_back(self, edge: Edge, reason: str = f"its merge check failed {MERGE_FAILS} times") -> Any:
        """Re-plan from the current observation (`replan`, at most `max_replans` times): REPLANNED with the new
        graph adopted, or False (recorded) when there is no re-planner or its budget is spent."""
        if self._may_replan():
            self._settle_hands(edge)
        return self._replan(f"the recovery of {edge.id} does not hold ({reason})")

    def _may_replan(self) -> bool:
        """AgentChord's fallback (branch mode) has a re-plan left; the backtracking variants keep to backtracking."""
        return (self.config.on_failure == "branch" and self.replan is not None
                and self.metrics.replans < self.config.max_replans)

    def _replan(self, why: str) -> Any:
        if self.replan is None or self.metrics.replans >= self.config.max_replans:
            self.log.event(self.robot.sim_time, "gave up", f"{why}; no re-plan left")
            return False
        self.metrics.replans += 1
        self.log.event(self.robot.sim_time, "replan", f"{why}; re-planning from the current observation "
                       f"({self.metrics.replans} of {self.config.max_replans})")
        try:
            graph = self.replan()
        except ReasoningError as exc:  # a refused plan, a model's reply unusable after its repair round, ...
            refused = isinstance(exc, PlanningError)
            self.log.event(self.robot.sim_time, "replan refused" if refused else "replan failed",
                           f"{'' if refused else type(exc).__name__ + ': '}{exc}; the trial ends as a failure")
            return False
        if graph is None:
            self.log.event(self.robot.sim_time, "goal check", "the re-planner finds the goal already holds")
            return self.goal_holds()
        self.adopt(graph)
        return REPLANNED

    def adopt(self, graph: TaskGraph) -> None:
        """Conduct `graph` from its start from now on (the trackers and counters carry over)."""
        self.graph, self.ctg = graph, cost_to_go(graph)
        self.synthesis.graph = graph
        self.goal_objects = {e for c in graph.node(graph.goal).constraints for e, role, _ in c.refs() if role != "arm"}

    def run_edge(self, edge: Edge, with_monitors: bool, stop: Callable[[Any], bool] | None = None) -> Firing | None:
        """Run the edge's actions under its monitors; the first firing, or None. `stop(action)`, asked after
        each action, ends the edge early (an outside watch fired)."""
        self.log.status(f"{edge.kind} {edge.id}")
        objs = objects_of(edge)
        monitors = list(edge.monitors) if with_monitors else []
        observers = getattr(self.robot, "step_observers", None)
        per_step = [m for m in monitors if observers is not None and proprioceptive(m.check)]
        # Sub-goal samples: one per atomic action, so one violated sample meets the window.
        sampled = [m.model_copy(update={"window": 1}) for m in monitors if m not in per_step]
        start = self._read(objs) if sampled else None
        bank = MonitorBank(sampled, start) if sampled else None
        fired: list[tuple[Firing, int]] = []
        watch = self._step_watch(per_step, fired) if per_step else None
        if watch is not None:
            observers.append(watch)
        try:
            for i, action in enumerate(edge.actions):
                if action.name == "open_gripper" and self._already_open(action.args.get("arm")):
                    continue
                if action.name == "place" and self._holds_nothing(action.args.get("arm")):
                    continue
                try:
                    self._execute(edge, action.name, dict(action.args))
                except Interrupted:  # the watch that stopped it (its firing, its loss) says what follows
                    pass
                if stop is not None and stop(action):
                    return None
                if fired:
                    firing, self.metrics.fired_at = fired[0]
                    self._fired(edge, firing)
                    return firing
                if with_monitors and self.after_action is not None and self.after_action(edge, i):
                    self.metrics.fired_at = self.robot_steps()
                    return Firing("verifier", "verify_failed", None, float("nan"), i)
                if bank is not None:
                    firing = bank.step(self._read(objs))
                    if firing is not None:
                        self.metrics.fired_at = self.robot_steps()
                        self._fired(edge, firing)
                        return firing
        finally:
            if watch is not None:
                observers.remove(watch)
        try:
            self.verify_pour(edge)
        except Interrupted:  # a loss while a turn is topped up: the recovery's watch has it
            pass
        return None

    def _already_open(self, arm: Any) -> bool:
        """The hand is commanded open (by this conductor, which waited for the fingers): opening it again only
        spends control steps. A pad still touching something does not matter: an open hand lets go of what it can."""
        if arm not in ARMS:
            return False
        return not self.robot.arm_state(arm).gripper_closed

    def _holds_nothing(self, arm: Any) -> bool:
        """No object is between the hand's pads: a place would lower the empty hand onto whatever is at the
        place (a recovery run again after a later drop re-ran the other arm's place of the cup it had already
        put down, and pressed the empty hand onto the cup)."""
        if arm not in ARMS:
            return False
        return not self.robot.arm_state(arm).held

    def _step_watch(self, monitors: list, fired: list) -> Callable[[Any], bool]:
        """The per-control-step observer: Eq. 12 over `GripSense`; True (interrupt the action) on a firing."""
        bank = MonitorBank(monitors)
        arms = sorted({e for m in monitors for e, role, _ in m.check.refs() if role == "arm"})
        sense = self.robot.grip_sense

        def watch(step: Any) -> bool:
            if fired:
                return True
            firing = bank.step(Features(arms={a: sense(a) for a in arms}))
            if firing is None:
                return False
            fired.append((firing, step.index))
            return True
        return watch

    def robot_steps(self) -> int:
        return int(getattr(self.robot, "control_steps", 0))

    def _fired(self, edge: Edge, firing: Firing) -> None:
        t = self.robot.sim_time
        self.metrics.firings.append(f"{edge.id}:{firing.failure_mode}")
        branch = self.config.on_failure == "branch"
        then = f"recovery {firing.recovery or 'none'}" if branch else "backtrack"
        self.log.event(t, "monitor", f"{firing.monitor} ({firing.failure_mode}) fired on {edge.id} with value "
                       f"{firing.value:.3g} -> {then}")
        if branch and firing.recovery is not None:
            self.log.transition(edge.id, firing.recovery)


    def _execute(self, edge: Edge, name: str, args: dict, unplanned_ok: bool = False) -> bool:
        """Run one atomic action; False when it could not be planned and `unplanned_ok` (nothing moved), else
        an unplannable action raises."""
        if self.metrics.actions >= self.config.max_actions:
            raise ConductorError(f"{self.config.max_actions} atomic actions spent without reaching the goal")
        call = {"action": name, **args}
        if name == "move_to_obj" and len(edge.actions) == 1:
            call = self._keyframe_call(edge, call)
        call = self.synthesis.adapt(edge, call)
        if self.metrics.fired_at is not None:  # the first command after a firing: detection -> recovery
            self.metrics.recovery_latency_steps.append(self.robot_steps() - self.metrics.fired_at)
            self.metrics.fired_at = None
        self.tops.before_grasp(call, self.robot.features)  # a knocked object's top, read again
        self.witness_release(call)
        result = self.robot.execute(call)
        if getattr(result, "unseen", False) and not unplanned_ok:
            result = self._look_again(call, result)
        if result.ik_failed and not unplanned_ok:
            result, call = self.reach_otherwise(edge, call, result)
        if name == "grasp" and isinstance(call.get("obj"), str):
            self.synthesis.grasp_outcome(call)
        arm_states = {a: self.robot.arm_state(a) for a in ARMS}
        self.tops.follow(arm_states)
        self.heads.follow(arm_states)
        self.metrics.actions += 1
        self.metrics.episode_steps += result.steps // self.steps_per_tick
        arm = result.arms[0] if result.arms else "right"
        tcp = self.robot.arm_state(arm).tcp_pos
        goal = {k: round(float(v), 4) for k, v in call.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
        self.log.skill(SkillLog(skill=call["action"], goal=goal, terminal={a: round(v * 1000, 2) for a, v in zip("xyz", tcp)},
                                reached=result.reached, recovery=edge.kind == "recovery", message=result.message,
                                sim_time=round(self.robot.sim_time, 4)))
        flag = ("reached" if result.reached else "IK FAILED" if result.ik_failed
                else "interrupted" if getattr(result, "interrupted", False) else "not reached")
        tag = "[magenta]recovery[/magenta] " if edge.kind == "recovery" else ""
        self.log.say(f"[dim]{self.robot.sim_time:6.2f}s[/dim] {tag}{escape(edge.id)}: [bold]{escape(call['action'])}"
                     f"[/bold] -> {flag} ({escape(result.message)})", markup=True)
        if getattr(result, "interrupted", False):
            raise Interrupted(f"{edge.id} {name}: {result.message}")
        if not result.planned and unplanned_ok:
            return False
        if result.ik_failed:
            raise Unreachable(f"{edge.id} {name}: {result.message}")
        if not result.planned:  # e.g. the object left the cameras' view (fell off the table): nothing moved, and
            # running it again in the same still scene would only refuse again
            raise ConductorError(f"{edge.id} {name} cannot be carried out: {result.message}")
        return True

    def _look_again(self, call: dict, result: Any) -> Any:
        """Its object is not seen (a hand between it and the cameras): every empty hand goes back out of the
        view, and the action is planned once more from a fresh look. The result of that second try."""
        self.log.event(self.robot.sim_time, "look again", f"{result.message}: the empty hands go back to clear "
                       "the cameras' view")
        for arm in ARMS:
            if arm in self.arms and self._holds_nothing(arm):
                back = self.robot.execute({"action": "back", "arm": arm})
                self.metrics.episode_steps += back.steps // self.steps_per_tick
        return self.robot.execute(call)

    def _keyframe_call(self, edge: Edge, call: dict) -> dict:
        arm = call["arm"]
        state = self.robot.arm_state(arm)
        held_names = sorted(state.held)
        refs = {e for c in self.graph.node(edge.target).constraints for e, role, _ in c.refs() if role != "arm"}
        objs = self.robot.features({call["obj"], *held_names, *refs})
        tcp = np.array(state.tcp_pos)
        held = {k: np.array(objs[k].centroid) - tcp for k in held_names if objs[k].centroid is not None}
        kf, move = self.keyframes.move_target(edge, self.graph.node(edge.target), objs, held, state,
                                              last=self.last.get(edge.id))
        self.last[edge.id] = kf.x
        self.metrics.keyframe_solves += 1
        return move

    def _read(self, objs) -> Features:  # noqa: ANN001 - names of objects
        """The feature vector the checks read: perceived objects plus the top this conductor tracks for each."""
        return features(self.robot, objs, tops=self.tops.world)

    def _still_at_rest(self, names: set[str]) -> bool:
        """The objects were read at rest and nothing has moved since (a merge into the goal need not wait again)."""
        return self._rested is not None and self._rested[0] == self.robot_steps() and names <= self._rested[1]

    def goal_holds(self) -> bool:
        goal = self.graph.node(self.graph.goal)
        names = self.goal_objects
        idle = ([a for a, state in goal.gripper.items() if state == "open"]  # else any open hand (a place's)
                or [a for a in ARMS if not self.robot.arm_state(a).gripper_closed])
        if idle and not self._still_at_rest(names):  # judge the scene at rest (a placed object may still rock)
            last = next(e for e in self.graph.edges if e.target == goal.id and e.kind == "nominal")
            if not self.wait_still(idle[0], names, last):
                self.log.event(self.robot.sim_time, "goal check", f"{', '.join(sorted(names))} still moving after "
                               f"{SETTLE_TRIES} reads; the goal is not reached at rest")
                return False
        f = self._read(names)
        values = [(c.kind, c.evaluate(f)) for c in strict(goal.constraints)]
        bad = [k for k, v in values if v > 0.0]
        unknown = [k for k, v in values if v != v]  # NaN: perception could not decide
        if bad or unknown:
            self.log.event(self.robot.sim_time, "goal check", f"goal {goal.id!r}: violated {', '.join(bad) or '-'}; "
                           f"undecided {', '.join(unknown) or '-'}")
        return not bad and not unknown and self.pours_done() and self.handovers_done()  # undecided is no success
