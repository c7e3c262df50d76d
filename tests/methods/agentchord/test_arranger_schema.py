"""The embedded arranger's reply always passes the arranger's own schema: a branch it cannot express within
the per-proposal bounds is left out with a note (the conductor re-plans for that failure), never a reply that
the reply check rejects as a whole, which would end the trial (`replan failed: BadReply`)."""

from __future__ import annotations

import pytest

import kintsugi.methods.agentchord.arranger as arranger
from kintsugi.methods.agentchord.composer import COMPOSER
from kintsugi.taskgraph.augment import parse_proposals
from tests.taskgraph_fixtures import arranger_request, composer_request


def test_a_branch_past_the_schema_bounds_is_left_out_with_a_note(monkeypatch: pytest.MonkeyPatch) -> None:
    request = composer_request()
    arrange = arranger_request(COMPOSER.embedded(request), request)
    real = arranger._branch
    calls = {"n": 0}

    def oversized(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        branch = real(*args, **kwargs)
        calls["n"] += 1
        if calls["n"] == 1:  # the first branch grows past any bound a reply may carry
            extra = [{"id": f"r.extra.{i}", "description": "filler"} for i in range(40)]
            branch = {**branch, "nodes": [*branch["nodes"], *extra]}
        return branch

    monkeypatch.setattr(arranger, "_branch", oversized)
    reply = arranger.embedded_arrange(arrange)
    assert calls["n"] > 1 and reply.proposals
    parse_proposals(list(reply.proposals))  # the whole reply is valid
    assert all(len(p["nodes"]) < 40 for p in reply.proposals)
    assert "no recovery (recovery proposal 0 rejected: nodes" in reply.reasoning


def test_a_branch_that_first_sees_how_the_object_lies_fits_the_bounds() -> None:
    """A multi-outcome branch (hub, then one chain per outcome) of 20 nodes, as real re-plans make, is valid."""
    opens = [{"name": "open_gripper", "args": {"arm": "right"}}]
    edge = {"id": "e1", "source": "s0", "target": "s1", "actions": opens}
    nodes = [{"id": f"r.{i}", "description": "step"} for i in range(20)]
    edges = [{**edge, "id": f"re.{i}", "source": "s0", "target": f"r.{i}"} for i in range(20)]
    monitor = {"id": "m", "failure_mode": "drop", "check": {"kind": "touching", "arm": "right", "object": "bottle"},
               "recovery": "re.0"}
    (proposal,) = parse_proposals([{"edge": "e1", "monitor": monitor, "nodes": nodes, "edges": edges}])
    assert len(proposal.nodes) == 20


def test_branches_that_would_take_the_graph_past_its_node_bound_are_left_out(monkeypatch: pytest.MonkeyPatch) -> None:
    from kintsugi.taskgraph.model import TaskGraph

    request = composer_request()
    arrange = arranger_request(COMPOSER.embedded(request), request)
    full = arranger.embedded_arrange(arrange)
    nominal = len(TaskGraph.from_data(arrange.graph).nodes)
    cap = nominal + sum(len(p["nodes"]) for p in full.proposals) // 2
    monkeypatch.setattr(arranger, "MAX_NODES", cap)
    cut = arranger.embedded_arrange(arrange)
    assert 0 < len(cut.proposals) < len(full.proposals)
    assert nominal + sum(len(p["nodes"]) for p in cut.proposals) <= cap
    assert f"the graph would exceed {cap} nodes" in cut.reasoning
