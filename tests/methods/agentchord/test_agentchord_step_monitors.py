"""Per-control-step monitoring: the robot's step observers see every control step and can interrupt an
action; the conductor's proprioceptive monitors fire inside the action (Eq. 12 window in control steps) and
the recovery's first command follows with a measured latency of zero control steps."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import pytest

from kintsugi.methods.agentchord.conducting import proprioceptive
from kintsugi.methods.agentchord.conductor import Conductor
from kintsugi.taskgraph.constraints import Detached, NotGrasped, Touching
from kintsugi.taskgraph.model import TaskGraph
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld
from kintsugi.core.log import TrialLog

START = {"bottle": StartPose(x=0.40, y=-0.25), "cup": StartPose(x=0.46, y=0.0)}


@pytest.fixture()
def robot():
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    yield TabletopRobot(world)
    world.close()


def test_observers_see_every_control_step_and_can_interrupt(robot: TabletopRobot) -> None:
    seen: list[int] = []
    robot.step_observers.append(lambda s: seen.append(s.step_in_action) and None)
    done = robot.execute({"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.05)})
    assert done.reached and not done.interrupted
    assert seen == list(range(1, len(seen) + 1)) and len(seen) == robot.control_steps
    assert done.steps == len(seen) * robot._world.steps_per_tick
    # A second observer stops the next action on its 7th control step; the first still sees every step.
    robot.step_observers.append(lambda s: s.step_in_action >= 7)
    seen.clear()
    cut = robot.execute({"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, -0.05)})
    assert cut.interrupted and not cut.reached and seen == list(range(1, 8))
    assert cut.steps == 7 * robot._world.steps_per_tick


def test_grip_sense_matches_the_full_arm_state(robot: TabletopRobot) -> None:
    robot.execute({"action": "grasp", "arm": "right", "obj": "bottle"})
    fast, full = robot.grip_sense("right"), robot.arm_state("right")
    assert fast.touching == {k for k, n in full.touching.items() if n == 2} == {"bottle"}
    assert fast.opening == pytest.approx(full.gripper_opening_m) and fast.closed == full.gripper_closed
    assert fast.eef == pytest.approx(full.tcp_pos)


def test_only_sensor_checks_run_per_step() -> None:
    assert proprioceptive(Touching(arm="right", object="bottle"))
    assert proprioceptive(NotGrasped(arm="right", min_opening=0.01))
    assert not proprioceptive(Detached(arm="right", object="bottle", tol=0.08))


def _carry_graph(window: int) -> TaskGraph:
    return TaskGraph.from_data({
        "task": "carry the bottle up", "start": "s0", "goal": "s2",
        "nodes": [{"id": "s0"}, {"id": "s1"}, {"id": "s2"}, {"id": "r1", "kind": "recovery"}],
        "edges": [
            {"id": "e1", "source": "s0", "target": "s1", "actions": [{"name": "grasp", "args": {"arm": "right", "obj": "bottle"}}]},
            {"id": "e2", "source": "s1", "target": "s2",
             "actions": [{"name": "move_by_offset", "args": {"arm": "right", "dxyz": [0.0, 0.0, 0.15]}}],
             "monitors": [{"id": "m.drop", "failure_mode": "drop", "check": {"kind": "touching", "arm": "right",
                           "object": "bottle"}, "margin": 0.0, "window": window, "recovery": "re1"}]},
            {"id": "re1", "source": "s1", "target": "r1", "kind": "recovery",
             "actions": [{"name": "open_gripper", "args": {"arm": "right"}}]},
            {"id": "re2", "source": "r1", "target": "s2", "kind": "recovery",
             "actions": [{"name": "open_gripper", "args": {"arm": "right"}}]},
        ]})


def test_a_drop_fires_within_the_action_after_the_window_and_recovery_starts_at_once(robot: TabletopRobot) -> None:
    graph = _carry_graph(window=4)
    log = TrialLog()
    conductor = Conductor(graph, robot, keyframes=None, log=log, steps_per_tick=1)
    assert conductor.run_edge(graph.edge("e1"), with_monitors=False) is None
    drop_at: list[int] = []

    def drop(step) -> None:  # noqa: ANN001 - an outside hand pulls the fingers open mid-lift
        if step.action == "move_by_offset" and step.step_in_action == 10:
            robot._world.force_open("right", 0.3)
            drop_at.append(step.index)
    robot.step_observers.append(drop)
    lift = graph.edge("e2")
    firing = conductor.run_edge(lift, with_monitors=True)
    robot.step_observers.remove(drop)
    assert drop_at and firing is not None and firing.failure_mode == "drop"
    # The pads stopped touching and stayed so for the window of 4 steps; the lift was cut at that step.
    assert firing.step >= 10 + 3
    assert conductor.metrics.fired_at == robot.control_steps < drop_at[0] + 40
    conductor._run_recovery(lift, firing)
    assert conductor.metrics.recovery_latency_steps == [0]
