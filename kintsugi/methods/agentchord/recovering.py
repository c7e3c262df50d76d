"""After a monitor fired: the recovery branch to its merge node, or a backtrack, and the re-check after it.

`branch` runs the pre-compiled recovery edge the firing maps to (Eq. 13) and the chain after it, each edge
watched by `LossWatch` and checked against its target's constraints (kintsugi.methods.agentchord.recovery_watch);
`backtrack` goes back to the latest nominal node whose sub-goal still holds. Either settles first: the failing
hand opens and the watched objects come to rest (kintsugi.methods.agentchord.settling).
"""

from __future__ import annotations

from typing import Any

from kintsugi.methods.agentchord.conducting import ConductorError, firing_arm, guard_objects, moves_an_arm, objects_of
from kintsugi.taskgraph.forward import guarded_next_edge, next_edge
from kintsugi.taskgraph.model import Edge
from kintsugi.taskgraph.monitor import Firing, MonitorBank


class Recovering:
    """The conductor's recoveries (a mixin of `Conductor`: it runs edges through the conductor's `run_edge` and
    reads through its `_read`)."""

    graph: Any
    robot: Any
    log: Any

    def _backtrack(self, failed: Edge, firing: Firing) -> str:
        """The latest nominal node before the failed edge whose constraints hold now (the start always does)."""
        arm = firing_arm(failed, firing)
        chain = self._nominal_path()
        upto = chain[: chain.index(failed.source) + 1]
        names = {e for n in upto for c in self.graph.node(n).constraints for e, role, _ in c.refs() if role != "arm"}
        if arm is not None:
            self.wait_still(arm, names | objects_of(failed), failed)
        f = self._read(names)
        for n in reversed(upto):
            if all(c.evaluate(f) <= 0.0 for c in self.graph.node(n).constraints):  # NaN (undecided) does not hold
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
        firing = MonitorBank(bound).step(self._read(objects_of(edge)))
        if firing is not None:
            self.metrics.fired_at = self.robot_steps()
            self._fired(edge, firing)
        return firing

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
            arm, objs = firing_arm(failed, firing), guard_objects(g, edge.target)
            if arm is not None and objs and moves_an_arm(edge):  # the edge may have nudged what the guards read (a hand
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
            self.merge_failed = True
            return f"{edge.target!r}: {bad} violated"
        return None

    def _settle(self, failed: Edge, recovery: Edge, firing: Firing) -> None:
        """Open the failing arm's gripper and keep it open until the objects its monitors watch have come to
        rest (two reads within SETTLE_M), so the recovery's perception-conditioned actions (a re-grasp) aim
        at where a dropped object lies, not where it was falling. Only the arm whose monitor fired: the other
        may still hold its own object (opening it dropped a fork while the spoon was recovered)."""
        arm = firing_arm(failed, firing)
        if arm is not None:
            self.wait_still(arm, objects_of(failed) | self.goal_objects, recovery)
