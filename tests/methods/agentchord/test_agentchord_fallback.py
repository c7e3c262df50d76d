"""A recovery that keeps failing its merge check falls back to re-planning from the current observation, a
bounded number of times, each recorded; with no re-planner or its budget spent the trial ends as a failure."""

from __future__ import annotations

from types import SimpleNamespace

from kintsugi.core.log import TrialLog
from kintsugi.methods.agentchord.conducting import ConductorConfig, Metrics
from kintsugi.methods.agentchord.conductor import MERGE_FAILS, REPLANNED, Conductor
from kintsugi.methods.agentchord.symbolic import PlanningError
from tests.taskgraph.test_taskgraph_forward import chain


def _conductor(replan=None, max_replans: int = 2, closed: dict | None = None) -> Conductor:  # noqa: ANN001
    c = Conductor.__new__(Conductor)  # only the fallback's state: no robot, nothing moves
    c.graph, c.replan, c.log = chain([1.0, 1.0]), replan, TrialLog()
    c.metrics, c.config = Metrics(), ConductorConfig(max_replans=max_replans)
    hands = closed or {}  # arm -> what it holds, for the hands commanded closed

    def arm_state(arm: str) -> SimpleNamespace:
        return SimpleNamespace(gripper_closed=arm in hands, held=frozenset(hands.get(arm, ())))

    c.robot = SimpleNamespace(sim_time=1.5, arm_state=arm_state)
    c.synthesis, c.pours, c.goal_objects = SimpleNamespace(graph=c.graph), {}, {"cup"}
    return c


def test_no_replanner_gives_up_with_the_reason() -> None:
    c = _conductor()
    assert c.fall_back(c.graph.edge("e0")) is False
    assert [e.kind for e in c.log.events] == ["gave up"] and f"failed {MERGE_FAILS} times" in c.log.events[0].detail


def test_replans_adopt_the_new_graph_until_the_budget_is_spent() -> None:
    new = chain([2.0, 2.0, 2.0])
    c = _conductor(lambda: new, max_replans=2)
    assert c.fall_back(c.graph.edge("e0")) is REPLANNED
    assert c.graph is new and c.synthesis.graph is new and c.ctg[new.start] == 6.0
    assert c.fall_back(c.graph.edge("e1")) is REPLANNED
    assert c.fall_back(c.graph.edge("e1")) is False  # the third: budget spent
    assert [e.kind for e in c.log.events] == ["replan", "replan", "gave up"] and c.metrics.replans == 2


def test_a_refused_replan_is_a_recorded_failure() -> None:
    def refuse():  # noqa: ANN202
        raise PlanningError("no plan reaches the goal from here")

    c = _conductor(refuse)
    assert c.fall_back(c.graph.edge("e0")) is False
    assert [e.kind for e in c.log.events] == ["replan", "replan refused"]


def test_the_run_figures_count_the_replans_and_old_records_read_as_none() -> None:
    from kintsugi.methods.agentchord.method import RunFigures

    old = dict(episode_steps=10, modelled_execution_time_s=1.0, latency_model_s=5.0, planning_reasoning_calls=2,
               runtime_reasoning_calls=0, recovery_latency_steps=[], recoveries=0, actions=3, graph_nodes=2,
               graph_edges=1, monitors=0)
    assert RunFigures(**old).replans == 0
    assert RunFigures(**old, replans=2).replans == 2


def test_a_hand_closed_on_nothing_it_holds_opens_and_the_scene_settles_before_the_replan() -> None:
    new = chain([2.0, 2.0])
    c = _conductor(lambda: new, closed={"left": (), "right": ("bottle",)})
    settled: list[tuple[str, set]] = []
    c.wait_still = lambda arm, objs, edge: settled.append((arm, set(objs))) or True  # type: ignore[method-assign]
    assert c.fall_back(c.graph.edge("e0")) is REPLANNED
    assert settled == [("left", {"cup"})]  # the right hand holds its bottle and stays closed
    c = _conductor(None, closed={"left": ()})
    c.wait_still = lambda arm, objs, edge: settled.append((arm, set(objs))) or True  # type: ignore[method-assign]
    assert c.fall_back(c.graph.edge("e0")) is False and len(settled) == 1  # no re-plan left: nothing to settle for
