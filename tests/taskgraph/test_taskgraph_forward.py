"""Eq. 8: recovery branches that move forward (or stay level) are kept, backward ones are dropped."""

from __future__ import annotations

import math

import pytest

from kintsugi.taskgraph.forward import cost_to_go, forward_filter
from kintsugi.taskgraph.model import TaskGraph
from tests.taskgraph_fixtures import VOCAB, act, pour_graph

WAIT = [act("wait")]


def chain(costs, extra_nodes=(), extra_edges=(), monitors=None):
    """Nominal chain n0 -> n1 -> ... with the given edge costs; goal is the last node."""
    monitors = monitors or {}
    nodes = [{"id": f"n{i}"} for i in range(len(costs) + 1)] + [dict(n, kind="recovery") for n in extra_nodes]
    edges = [{"id": f"e{i}", "source": f"n{i}", "target": f"n{i + 1}", "cost": c, "actions": WAIT,
              "monitors": monitors.get(f"e{i}", [])} for i, c in enumerate(costs)]
    edges += [dict(e, kind="recovery", actions=WAIT) for e in extra_edges]
    return TaskGraph.from_data({"start": "n0", "goal": f"n{len(costs)}", "nodes": nodes, "edges": edges}, VOCAB)


def mon(mid, recovery):
    return {"id": mid, "failure_mode": "drop", "recovery": recovery,
            "check": {"kind": "visibility", "object": "cup", "n_min": 10}}


def test_pour_graph_keeps_forward_and_level_rejects_backward():
    r = forward_filter(pour_graph())
    assert {b.edge for b in r.kept} == {"r_retry", "r_merge"}
    (back,) = r.rejected
    assert (back.edge, back.context, back.via, back.merge, back.monitors) == ("r_home", "grasped", "reset", "home", ("m_cup",))
    assert back.cost_context == 120 and back.cost_merge == 160
    assert back.reason.startswith("moves backward")
    g = r.graph
    assert "reset" not in g.node_map and not {"r_reset", "r_home"} & set(g.edge_map)
    assert [m.recovery for m in g.edge("e_carry").monitors] == ["r_pick", None]  # m_cup still detects
    assert r.cost_to_go == {"home": 160, "grasped": 120, "over_cup": 60, "poured": 30, "done": 0, "regrasp": 125}


def test_skip_ahead_kept_and_backward_direct_edge_rejected():
    g = chain([10, 10, 10], monitors={"e1": [mon("fwd", "r_fwd")], "e2": [mon("bwd", "r_bwd")]},
              extra_edges=[{"id": "r_fwd", "source": "n1", "target": "n3", "cost": 50},
                           {"id": "r_bwd", "source": "n2", "target": "n0", "cost": 1}])
    r = forward_filter(g)
    assert [b.edge for b in r.kept] == ["r_fwd"] and [b.edge for b in r.rejected] == ["r_bwd"]
    assert r.graph.edge("e2").monitors[0].recovery is None
    assert "r_bwd" not in r.graph.edge_map


def test_failure_only_edges_do_not_shorten_cost_to_go():
    g = chain([10, 10, 10], monitors={"e0": [mon("m", "r_jump")]},
              extra_edges=[{"id": "r_jump", "source": "n0", "target": "n3", "cost": 1}])
    assert cost_to_go(g)["n0"] == 30  # not 1: the jump runs only when the monitor fires


def test_costs_are_physical_not_hops():
    # Branch A (n1 -> a -> n4, cheap) vs. nominal (n1 -> n2 -> n3 -> n4); merging at n2 costs more than at n1?
    g = TaskGraph.from_data({
        "start": "n0", "goal": "n3",
        "nodes": [{"id": "n0"}, {"id": "n1"}, {"id": "n2"}, {"id": "n3"}, {"id": "rec", "kind": "recovery"}],
        "edges": [
            {"id": "a", "source": "n0", "target": "n1", "cost": 5, "actions": WAIT, "monitors": [mon("m", "r_in")]},
            {"id": "b", "source": "n1", "target": "n3", "cost": 100, "actions": WAIT},
            {"id": "c", "source": "n0", "target": "n2", "cost": 50, "actions": WAIT},
            {"id": "d", "source": "n2", "target": "n3", "cost": 60, "actions": WAIT},
            {"id": "r_in", "kind": "recovery", "source": "n0", "target": "rec", "cost": 1, "actions": WAIT},
            {"id": "r_n1", "kind": "recovery", "source": "rec", "target": "n1", "cost": 1, "actions": WAIT},
            {"id": "r_n2", "kind": "recovery", "source": "rec", "target": "n2", "cost": 1, "actions": WAIT},
        ],
    }, VOCAB)
    # C(n0) = min(5 + 100, 50 + 60) = 105; C(n1) = 100 (kept); C(n2) = 60 (kept, on the other strategy).
    r = forward_filter(g)
    assert {b.edge for b in r.kept} == {"r_n1", "r_n2"}
    g2 = TaskGraph.from_data(g.model_dump() | {"edges": [
        e.model_dump() | ({"cost": 200} if e.id == "b" else {}) for e in g.edges]}, VOCAB)
    # Now C(n0) = 110 via c; C(n1) = 200 > 110: merging into n1 is backward although it is "downstream" of n0.
    r2 = forward_filter(g2)
    assert [b.edge for b in r2.kept] == ["r_n2"] and [b.edge for b in r2.rejected] == ["r_n1"]
    assert "rec" in r2.graph.node_map  # still merges through r_n2


def test_branch_that_never_merges_is_dropped_with_its_entry():
    g = chain([10, 10], extra_nodes=[{"id": "stuck"}], monitors={"e1": [mon("m", "r_in")]},
              extra_edges=[{"id": "r_in", "source": "n1", "target": "stuck"}])
    r = forward_filter(g)
    (b,) = r.rejected
    assert b.edge is None and b.via == "stuck" and b.monitors == ("m",) and "never merges" in b.reason
    assert "stuck" not in r.graph.node_map and "r_in" not in r.graph.edge_map
    assert r.graph.edge("e1").monitors[0].recovery is None


def test_chain_of_recovery_nodes_dropped_when_its_only_merge_is_backward():
    g = chain([10, 10, 10], extra_nodes=[{"id": "a"}, {"id": "b"}], monitors={"e2": [mon("m", "r1")]},
              extra_edges=[{"id": "r1", "source": "n2", "target": "a"}, {"id": "r2", "source": "a", "target": "b"},
                           {"id": "r3", "source": "b", "target": "n1"}])
    r = forward_filter(g)
    assert [b.edge for b in r.rejected] == ["r3"] and r.kept == ()
    assert set(r.graph.node_map) == {"n0", "n1", "n2", "n3"}
    assert all(e.kind == "nominal" for e in r.graph.edges)


def test_level_merge_is_kept_and_filter_is_idempotent():
    g = chain([10, 10], monitors={"e1": [mon("m", "retry")]},
              extra_edges=[{"id": "retry", "source": "n1", "target": "n1", "cost": 3}])
    r = forward_filter(g)
    assert [b.edge for b in r.kept] == ["retry"] and r.kept[0].cost_merge == r.kept[0].cost_context == 10
    again = forward_filter(r.graph)
    assert again.graph == r.graph and again.rejected == ()


def test_cost_to_go_infinite_only_off_the_goal_path():
    ctg = cost_to_go(chain([1.5, 2.5]))
    assert ctg == {"n0": 4.0, "n1": 2.5, "n2": 0.0}
    assert not any(math.isinf(v) for v in ctg.values())


@pytest.mark.parametrize("graph", [pour_graph()])
def test_kept_branches_satisfy_eq8_on_the_result(graph):
    r = forward_filter(graph)
    for b in r.kept:
        assert r.cost_to_go[b.merge] <= r.cost_to_go[b.context]
