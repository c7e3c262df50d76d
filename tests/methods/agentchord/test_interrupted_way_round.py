"""An action's way round (the drag of a lying object back into reach) stops at the first move a step observer
interrupts: the watch that stopped it (a recovery's loss watch, a monitor) decides what follows. Going on
would have every further move stopped at its first control step: pushes that move nothing, and a trial that
ends as if no arm could reach the object. The conductor's own `_execute` on a real robot."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
from types import SimpleNamespace

import pytest

from kintsugi.methods.agentchord.conducting import ConductorConfig, Interrupted, Metrics
from kintsugi.methods.agentchord.conductor import Conductor
from kintsugi.methods.agentchord.tops import Heads, Tops
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.world import TabletopWorld
from tests.worlds.tabletop.test_tabletop_push import START, lay

EDGE = SimpleNamespace(id="re_lying", kind="recovery", actions=())


class Log:
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []
        self.skills: list = []

    def event(self, t: float, kind: str, detail: str) -> None:
        self.events.append((kind, detail))

    def skill(self, s) -> None:  # noqa: ANN001
        self.skills.append(s)

    def say(self, *_a, **_k) -> None:
        pass


class Adapt:
    def adapt(self, edge, call: dict) -> dict:  # noqa: ANN001
        return call

    def grasp_outcome(self, call: dict) -> None:
        pass


def _conductor(robot: TabletopRobot) -> Conductor:
    c = Conductor.__new__(Conductor)
    c.robot, c.log, c.steps_per_tick, c.arms = robot, Log(), 1, {"left", "right"}
    c.config, c.metrics, c.synthesis, c.tops, c.heads = ConductorConfig(), Metrics(), Adapt(), Tops(), Heads()
    return c


class LatchOnClose:
    """A loss watch that has fired: once the right hand closes, every later control step is interrupted."""

    def __init__(self, robot: TabletopRobot) -> None:
        self.robot, self.latched = robot, False

    def __call__(self, step) -> bool:  # noqa: ANN001
        self.latched = self.latched or self.robot.grip_sense("right").closed
        return self.latched


@pytest.mark.parametrize("watched", [False, True])
def test_a_way_round_stops_at_the_first_interrupted_move(watched: bool) -> None:
    world = TabletopWorld(TabletopConfig(), ["bottle", "cup"], START)
    try:
        lay(world, "bottle", 0.62, -0.30)
        robot = TabletopRobot(world)
        c = _conductor(robot)
        f = robot.features({"bottle"})["bottle"]
        call = {"action": "grasp", "arm": "right", "obj": "bottle"}
        if watched:
            robot.step_observers.append(LatchOnClose(robot))
            with pytest.raises(Interrupted):
                c.pull_into_reach(EDGE, call, f)
            # the drag's grasp ran (the hand closed, then the watch stopped it); no move after it was issued
            assert [s.skill for s in c.log.skills] == ["grasp"], [s.skill for s in c.log.skills]
        else:
            assert c.pull_into_reach(EDGE, call, f)
            assert [s.skill for s in c.log.skills] == ["grasp", "move_by_offset", "move_by_offset", "move_by_offset",
                                                       "open_gripper", "move_by_offset"]
    finally:
        world.close()
