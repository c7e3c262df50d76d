"""The conductor: runs a compiled recovery-augmented graph on the tabletop robot, with no reasoning calls.

From the start node it takes the cheapest nominal edge to the goal (`next_edge`), runs its atomic actions
(a `move_to_obj` goes to its keyframe, re-solved with the latest features just before it runs, warm-started
from the compiled one), and evaluates the edge's monitors (Eq. 12).

Two sampling rates, by what a monitor reads:
- proprioceptive monitors (gripper opening, finger-pad touch: a drop, a missed grasp) are evaluated every
  control step through the robot's per-step observer hook, on `GripSense` (encoders and pads, no images),
  with their persistence window W in control steps; a firing interrupts the running action in that control
  step and the pre-compiled recovery edge it maps to (Eq. 13) issues the next command;
- monitors over perceived object features (drift, upright, slip by centroid) are evaluated on full
  perception after every atomic action (a sub-goal sample; one violated sample meets their window), since a
  render per control step would cost far more than the step itself.
A recovery's chain runs to its merge node; the failed edge's monitors are read once more there (a recovery
that did not hold is run again, up to `max_recoveries`), and nominal execution continues. Recovery latency is
measured in control steps from the firing to the recovery's first command (`Metrics.recovery_latency_steps`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import numpy as np
from rich.markup import escape

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import KintsugiError
from kintsugi.methods.agentchord.keyframes import KeyframeError, TabletopKeyframes
from kintsugi.methods.agentchord.observe import ARMS, features
from kintsugi.methods.agentchord.synthesis import EdgeSynthesis
from kintsugi.methods.agentchord.tops import Heads, Tops
from kintsugi.perception.features import ObjectFeatures
from kintsugi.taskgraph.features import Features
from kintsugi.taskgraph.forward import cost_to_go, guarded_next_edge, next_edge
from kintsugi.taskgraph.model import Edge, TaskGraph
from kintsugi.taskgraph.monitor import Firing, MonitorBank
from kintsugi.core.record import SkillLog
from kintsugi.core.log import TrialLog


SETTLE_M = 0.0003
"""Two reads of every watched centroid this close (about 0.1 s apart)... (renders are deterministic, so a
still object reads the same twice; a bottle rocking on its base after a drop moves its centroid ~1 mm)"""
SETTLE_DEG = 0.2
"""...and of every watched principal axis this close in angle: the objects are at rest."""
SETTLE_READS = 2
"""Consecutive still pairs required (one pair can alias with a rocking object's period)."""
SETTLE_TRIES = 25
CAUGHT_CLEAR_M = 0.02
"""An object whose lowest perceived point is this far above the table does not rest on it."""
MAX_SET_DOWNS = 2
SET_DOWN_TRIES = 6
SET_DOWN_MARGIN_M = 0.03
"""A caught object is set down this far (beyond both objects' half extents) from every other object."""


class ConductorError(KintsugiError):
    """The conductor cannot go on (action budget spent, a recovery node with no way back)."""


class ConductorConfig(StrictModel):
    max_actions: int = 200
    """Atomic actions per episode before the conductor gives up (a recovery loop never ends a trial hanging)."""
    max_recoveries: int = 10
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
    fired_at: int | None = None
    """Control step of the latest firing whose recovery has not issued its first command yet."""


def proprioceptive(check: Any) -> bool:
    """A check that reads only the arms' own sensors (no perceived object geometry): per-control-step."""
    return all(role == "arm" or feature is None for _, role, feature in check.refs())


def _moves(edge: Edge) -> bool:
    """The edge moves an arm (anything but opening a hand, which the settle before it has just done while the
    objects came to rest)."""
    return any(a.name != "open_gripper" for a in edge.actions)


def _guard_objects(graph: TaskGraph, node: str) -> set[str]:
    return {e for x in graph.out_edges(node) for c in x.guard for e, role, _ in c.refs() if role != "arm"}


def firing_arm(edge: Edge, firing: Firing) -> str | None:
    """The arm the fired monitor watches (the first arm any of the edge's monitors reads when it names none)."""
    mine = [m for m in edge.monitors if m.id == firing.monitor] or list(edge.monitors)
    return next((e for m in mine for e, role, _ in m.check.refs() if role == "arm"), None)


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
        self._rested: tuple[int, frozenset[str]] | None = None
        """(control step, objects) of the last read that found those objects at rest."""

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
                if node is None:  # the recovery was itself disturbed (a drop, a missed grasp): run it again
                    continue
                # Read the failed edge's monitors again only where they still apply (a merge past its target,
                # e.g. a release straight to the goal, leaves the hand empty on purpose).
                firing = self._recheck(edge) if node == edge.target else None
        return self.goal_holds()

    def run_edge(self, edge: Edge, with_monitors: bool, stop: Callable[[Any], bool] | None = None) -> Firing | None:
        """Run the edge's actions under its monitors; the first firing, or None. `stop(action)`, asked after
        each action, ends the edge early (an outside watch fired)."""
        self.log.status(f"{edge.kind} {edge.id}")
        objs = _objects_of(edge)
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
                self._execute(edge, action.name, dict(action.args))
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
        return None

    def _already_open(self, arm: Any) -> bool:
        """The hand is commanded open (by an action of this conductor's, which waited for the fingers): opening
        it again would only spend control steps (a recovery's release right after the settle, which has just
        opened that hand). Whether a pad still touches something does not matter: an open hand lets go of what
        it can (a bottle that fell upright against an open finger cost pour-single seed 3 a second opening, 9
        steps more than rekep)."""
        if arm not in ARMS:
            return False
        return not self.robot.arm_state(arm).gripper_closed

    def _holds_nothing(self, arm: Any) -> bool:
        """No object is between the hand's pads: a place would lower the empty hand onto whatever is at the
        place (a recovery run again after a later drop re-ran the other arm's place of the cup it had already
        put down, and pressed the empty hand onto the cup)."""
        if arm not in ARMS:
            return False
        return not any(n == 2 for n in self.robot.arm_state(arm).touching.values())

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

    def _backtrack(self, failed: Edge, firing: Firing) -> str:
        """The latest nominal node before the failed edge whose constraints hold now (the start always does)."""
        arm = firing_arm(failed, firing)
        chain = self._nominal_path()
        upto = chain[: chain.index(failed.source) + 1]
        names = {e for n in upto for c in self.graph.node(n).constraints for e, role, _ in c.refs() if role != "arm"}
        if arm is not None:
            self.wait_still(arm, names | _objects_of(failed), failed)
        f = self._read(names)
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
        """After a recovery merged: the failed edge's monitors that need no edge-start reference, read once, but
        not the drop checks (touch): `LossWatch` judged those during the recovery with Eq. 12's window, as the
        nominal edge's watch does. Read once more here, a hand that lost touch in the last control steps of a
        two-arm carry (the tray set on the table slid out of the left pads) fired with no window, and the same
        recovery ran again and again (coffee-tray seed 13: four times, 1780 steps against rekep's 1240)."""
        bound = [m.model_copy(update={"window": 1}) for m in edge.monitors
                 if m.check.bound and m.check.kind != "touching"]
        if not bound:
            return None
        firing = MonitorBank(bound).step(self._read(_objects_of(edge)))
        if firing is not None:
            self.metrics.fired_at = self.robot_steps()
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

    def _run_recovery(self, failed: Edge, firing: Firing) -> str | None:
        """The recovery chain from the failure context to its merge node; returns the merge node, or None when
        the recovery itself was disturbed (a held object dropped, a grasp closed on nothing): the caller runs
        the same recovery again, since the failure context and its predicted state are the same."""
        from kintsugi.methods.agentchord.recovery_watch import held_in_failure, named

        g = self.graph
        edge = g.edge(firing.recovery)
        self._settle(failed, edge, firing)
        # Watched for a loss: what the failure context held and what the recovery has taken hold of so far. Not
        # whatever else the pads touch: a hand closing on a capsule that stands in the tray pinches the tray's
        # wall too, and lifting the capsule out of that pinch is no drop (coffee-tray seed 70 ran its recovery
        # again for the tray's "loss" ten times, and gave up).
        held = held_in_failure(failed)
        while True:
            held |= named(edge)
            again = self._run_watched(edge, held)
            if again is not None:
                self.log.event(self.robot.sim_time, "recovery disturbed", f"{edge.id}: {again}; run it again")
                return None  # the run again settles first (settling here too waited out three more reads)
            if g.node(edge.target).kind == "nominal":
                return edge.target
            arm, objs = firing_arm(failed, firing), _guard_objects(g, edge.target)
            if arm is not None and objs and _moves(edge):  # the edge may have nudged what the guards read (a hand
                self.wait_still(arm, objs, edge)  # rising past a bottle leaning on the held cup): read it at rest
            nxt, matched = guarded_next_edge(g, edge.target, self._read(objs), self.ctg)
            if nxt is None:  # cannot happen on an Eq. 8-filtered graph: every recovery node merges
                raise ConductorError(f"recovery node {edge.target!r} has no way back into the graph")
            if not matched:
                self.log.event(self.robot.sim_time, "branch", f"no guard out of {edge.target!r} holds; "
                               f"taking the cheapest, {nxt.id!r}")
            edge = nxt

    def _run_watched(self, edge: Edge, held: set[str]) -> str | None:
        """One recovery edge under `LossWatch` (a loss of what the recovery holds, `held`), then its target's
        constraints; what went wrong, or None."""
        from kintsugi.methods.agentchord.recovery_watch import LossWatch, unmet, watched

        watch = LossWatch(self.robot, held)
        observers = getattr(self.robot, "step_observers", None)
        if observers is not None:
            observers.append(watch)
        try:
            self.run_edge(edge, with_monitors=False, stop=lambda a: watch.check_grasp(a) is not None)
        finally:
            if observers is not None:
                observers.remove(watch)
        if watch.lost is not None:
            self.metrics.fired_at = watch.at
            return watch.lost
        node = self.graph.node(edge.target)
        bad = unmet(node, self._read(watched(node))) if node.constraints else None
        if bad is not None:
            self.metrics.fired_at = self.robot_steps()
            return f"{edge.target!r}: {bad} violated"
        return None

    def _settle(self, failed: Edge, recovery: Edge, firing: Firing) -> None:
        """Open the failing arm's gripper and keep it open until the objects its monitors watch have come to
        rest (two reads within SETTLE_M), so the recovery's perception-conditioned actions (a re-grasp) aim
        at where a dropped object lies, not where it was falling. Only the arm whose monitor fired: the other
        may still hold its own object (opening it dropped a fork while the spoon was recovered)."""
        arm = firing_arm(failed, firing)
        if arm is not None:
            self.wait_still(arm, _objects_of(failed) | self.goal_objects, recovery)

    def wait_still(self, arm: str, objs: set[str], edge: Edge) -> bool:
        """True once the objects are at rest; False if they still move after SETTLE_TRIES reads."""
        if not objs:
            return True
        prev, still, set_downs = None, 0, 0
        for _ in range(SETTLE_TRIES):
            self._execute(edge, "open_gripper", {"arm": arm})
            now = self.robot.features(objs)
            self.tops.observe(now)
            self.heads.observe(now)
            seen = [now[k] for k in sorted(objs) if now[k].centroid is not None]
            pts = np.array([f.centroid for f in seen], dtype=float).reshape(-1, 3)  # none seen: (0, 3)
            axes = [None if f.axis is None else np.asarray(f.axis, dtype=float) for f in seen]
            moved = prev is None or pts.shape != prev[0].shape or not np.all(np.linalg.norm(pts - prev[0], axis=1) < SETTLE_M)
            if not moved:
                for a, b in zip(axes, prev[1]):
                    if (a is None) != (b is None):
                        moved = True
                    elif a is not None:
                        cos = abs(float(a @ b)) / max(float(np.linalg.norm(a) * np.linalg.norm(b)), 1e-12)
                        moved = moved or np.degrees(np.arccos(min(1.0, cos))) > SETTLE_DEG
            still = 0 if moved else still + 1
            if still >= SETTLE_READS:
                if set_downs < MAX_SET_DOWNS and self._set_down_caught(arm, now, edge):
                    set_downs, prev, still = set_downs + 1, None, 0
                    continue
                if hasattr(self.robot, "control_steps"):
                    self._rested = (self.robot_steps(), frozenset(objs))
                return True
            prev = (pts, axes)
        return False

    def _set_down_caught(self, arm: str, seen: dict, edge: Edge) -> bool:
        """An object that came to rest in the open hand (both finger pads touch it, and it hangs clear of the
        table) is closed on, turned top up when its top is known (its pose in the hand read again first), and set
        down at the nearest spot clear of every other object; True if one was. A bottle dropped while the hand
        was turned over to pour fell across the open fingers and stayed there; the re-grasp's rise to its pose
        above carried it along and flung it out of reach (pour-dual seeds 86 and 88). Set down straight below,
        it lay where the other hand was lowering the cup."""
        touching = self.robot.arm_state(arm).touching
        caught = [k for k in sorted(seen) if touching.get(k) == 2 and seen[k].centroid is not None
                  and seen[k].extremes and seen[k].extremes["bottom"][2] > CAUGHT_CLEAR_M]
        if not caught:
            return False
        obj = caught[0]
        self.log.event(self.robot.sim_time, "caught", f"{obj} rests in the open {arm} hand: set it down")
        self._execute(edge, "close_gripper", {"arm": arm})
        self.tops.regrip(arm, obj, self.robot.features({obj}), self.robot.arm_state(arm))
        turn = self.synthesis.upright_call({"action": "rotate_eef", "arm": arm, "angle_deg": 0.0, "axis": "closing"})
        if turn["action"] == "move_by_offset":  # its top is known: stand it on its base
            self._execute(edge, "move_by_offset", {k: v for k, v in turn.items() if k != "action"})
        others = [f for k, f in self.robot.features().items() if k != obj and f.centroid is not None]
        for x, y in set_down_spots(seen[obj], others, self.robot.bases[arm])[:SET_DOWN_TRIES]:
            if self._execute(edge, "place", {"arm": arm, "x": round(x, 4), "y": round(y, 4)}, unplanned_ok=True):
                return True
        self._execute(edge, "open_gripper", {"arm": arm})
        return True

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
        result = self.robot.execute(call)
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
        if not result.planned and unplanned_ok:
            return False
        if result.ik_failed:
            raise KeyframeError(f"{edge.id} {name}: {result.message}")
        if not result.planned:  # e.g. the object left the cameras' view (fell off the table): nothing moved, and
            # running it again in the same still scene would only refuse again
            raise ConductorError(f"{edge.id} {name} cannot be carried out: {result.message}")
        return True

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

    def _read(self, objs) -> Features:  # noqa: ANN001 - names of objects
        """The feature vector the checks read: perceived objects plus the top this conductor tracks for each."""
        return features(self.robot, objs, tops=self.tops.world)

    def _still_at_rest(self, names: set[str]) -> bool:
        """The objects were read at rest and nothing has moved since (no control step): a recovery that let a
        dropped bottle come to rest and merged straight into the goal waited for it a second time, three reads
        (24 control steps) more than a re-planner that found the goal already held (pour-single seed 41)."""
        return self._rested is not None and self._rested[0] == self.robot_steps() and names <= self._rested[1]

    def goal_holds(self) -> bool:
        goal = self.graph.node(self.graph.goal)
        names = self.goal_objects
        idle = [a for a, state in goal.gripper.items() if state == "open"]
        if idle and not self._still_at_rest(names):  # judge the scene at rest (a placed object may still rock)
            last = next(e for e in self.graph.edges if e.target == goal.id and e.kind == "nominal")
            if not self.wait_still(idle[0], names, last):
                self.log.event(self.robot.sim_time, "goal check", f"{', '.join(sorted(names))} still moving after "
                               f"{SETTLE_TRIES} reads; the goal is not reached at rest")
                return False
        f = self._read(names)
        values = [(c.kind, c.evaluate(f)) for c in goal.constraints]
        bad = [k for k, v in values if v > 0.0]
        unknown = [k for k, v in values if v != v]  # NaN: perception could not decide
        if bad or unknown:
            self.log.event(self.robot.sim_time, "goal check", f"goal {goal.id!r}: violated {', '.join(bad) or '-'}; "
                           f"undecided {', '.join(unknown) or '-'}")
        return not bad


def set_down_spots(obj: ObjectFeatures, others: list[ObjectFeatures], base: np.ndarray) -> list[tuple[float, float]]:
    """Table spots (x, y) to set a caught object down at, nearest first (ties: nearer the arm's base, easier
    to reach): below where it hangs, or rings around that 5 cm apart, clear of every other object's extent."""
    c = np.asarray(obj.centroid, dtype=float)[:2]
    half = max(obj.extent or (0.0,)) / 2.0
    spots = [c] + [c + r * np.array([np.cos(a), np.sin(a)]) for r in np.arange(0.05, 0.31, 0.05)
                   for a in np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)]
    spots.sort(key=lambda p: (round(float(np.linalg.norm(p - c)), 3), float(np.linalg.norm(p - base[:2]))))

    def clear(p: np.ndarray) -> bool:
        return all(np.linalg.norm(p - np.asarray(o.centroid, dtype=float)[:2])
                   >= half + max(o.extent or (0.0,)) / 2.0 + SET_DOWN_MARGIN_M for o in others)

    return [(float(p[0]), float(p[1])) for p in spots if clear(p)]

