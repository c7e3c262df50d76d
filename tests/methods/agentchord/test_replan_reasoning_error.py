"""A reasoning error while re-planning (a model's reply unusable after its repair round, an endpoint down) is a
recorded failure of the trial with the reason, as a refused re-plan is: never a trial error.

The conductor's fallback re-plans through AgentChord's own re-planner on a real observation of pour-single, with
the scripted backend answering the re-plan's composer call with a failure."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import pytest

from kintsugi.core.record import ReasonerSettings
from kintsugi.methods.agentchord.method import AgentChord
from kintsugi.methods.agentchord.reaching import Unreachable
from kintsugi.reasoning import make_reasoner
from kintsugi.reasoning.base import RecordingReasoner
from kintsugi.worlds.tabletop.pour_single import SPEC
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.worlds.tabletop.task import TabletopTask
from tests.methods.agentchord.test_agentchord_fallback import _conductor


@pytest.fixture(scope="module")
def robot():  # noqa: ANN201
    task = TabletopTask(SPEC)
    cfg = task.config_type()
    world, *_ = task.build(cfg, "none", 41000)
    yield TabletopRobot(world), cfg
    world.close()


def _scripted(tmp_path: Path) -> RecordingReasoner:
    path = tmp_path / "replies.jsonl"
    path.write_text(json.dumps({"role": "composer", "error": "the endpoint did not answer"}) + "\n")
    return RecordingReasoner(make_reasoner(ReasonerSettings(backend="scripted", options={"replies": str(path)})),
                             records=[])


def test_a_reasoning_error_while_re_planning_is_a_recorded_failure(robot, tmp_path: Path) -> None:  # noqa: ANN001
    rob, cfg = robot
    reasoner = _scripted(tmp_path)
    method = AgentChord(SimpleNamespace(task=SPEC, cfg=cfg, reasoner=reasoner))
    c = _conductor()
    c.robot = rob
    first = rob.observation(images=False)
    c.replan = method._replanner(reasoner, c, rob, first, ["upright(bottle)", "on_table(bottle)"])

    def out_of_reach():  # noqa: ANN202 - the first traversal meets an action no arm reaches
        c._traverse = lambda: pytest.fail("the trial went on after the re-plan failed")
        raise Unreachable("grasp(right, bottle): out of reach")

    c._traverse = out_of_reach
    assert c.run() is False  # the method's verdict: a failure, not an exception
    kinds = [e.kind for e in c.log.events]
    assert kinds == ["unreachable", "replan", "replan failed"], [(e.kind, e.detail) for e in c.log.events]
    failed = c.log.events[-1].detail
    assert "ReasoningError" in failed and "the endpoint did not answer" in failed and "ends as a failure" in failed
    assert c.metrics.replans == 1
    assert [(r.role, r.reply) for r in reasoner.records] == [("composer", None)]
    assert "the endpoint did not answer" in reasoner.records[0].error  # in the transcript too


def test_a_refused_re_plan_is_still_told_apart(tmp_path: Path) -> None:
    from kintsugi.methods.agentchord.symbolic import PlanningError

    def refuse():  # noqa: ANN202
        raise PlanningError("no plan reaches the goal from here")

    c = _conductor(refuse)
    assert c.fall_back(c.graph.edge("e0")) is False
    assert [e.kind for e in c.log.events] == ["replan", "replan refused"]
    assert c.log.events[-1].detail.startswith("no plan reaches the goal from here")
