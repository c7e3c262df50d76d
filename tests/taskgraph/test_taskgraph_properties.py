"""Properties on random graphs: cost-to-go is a true shortest-path cost, Eq. 8 never keeps a backward
branch, filtering is idempotent and leaves the nominal plan alone, and JSON round trips exactly."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from kintsugi.taskgraph.forward import cost_to_go, forward_filter, traversable
from kintsugi.taskgraph.model import TaskGraph
from tests.taskgraph_fixtures import VOCAB, act

SETTINGS = settings(max_examples=100, deadline=None, derandomize=True)
WAIT = [act("wait")]
finite = st.floats(0.0, 1.0, allow_nan=False)
cost = st.floats(0.5, 100.0, allow_nan=False)
point = st.builds(lambda e, o: {"entity": e, "offset": list(o)}, st.sampled_from(["cup", "bottle", "left"]),
                  st.tuples(finite, finite, finite))
constraint = st.one_of(
    st.builds(lambda p, t, r: {"kind": "drift", "point": p, "tol": t, "ref": r}, point, finite,
              st.none() | st.tuples(finite, finite, finite).map(list)),
    st.builds(lambda o, t: {"kind": "upright", "object": o, "tol_deg": t}, st.sampled_from(["cup", "bottle"]),
              st.floats(0.5, 90.0)),
    st.builds(lambda a, m: {"kind": "not_grasped", "arm": a, "min_opening": m}, st.sampled_from(["left", "right"]), finite),
    st.builds(lambda o, n: {"kind": "visibility", "object": o, "n_min": n}, st.sampled_from(["cup", "bottle"]),
              st.integers(1, 5000)),
    st.builds(lambda a, b, t: {"kind": "misaligned", "a": a, "b": b, "tol": t}, point, point, finite),
    st.builds(lambda a, b, g: {"kind": "above", "a": a, "b": b, "min_gap": g}, point, point, finite),
)


@st.composite
def graphs(draw) -> dict:
    n = draw(st.integers(2, 8))
    nodes = [{"id": f"n{i}"} for i in range(n)]
    edges = [{"id": f"e{i}", "source": f"n{i}", "target": f"n{i + 1}", "cost": draw(cost), "actions": WAIT}
             for i in range(n - 1)]
    for k, (i, j) in enumerate(draw(st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)), max_size=6))):
        edges.append({"id": f"x{k}", "source": f"n{i}", "target": f"n{j}", "cost": draw(cost), "actions": WAIT})
    n_nominal = len(edges)
    for k in range(draw(st.integers(0, 6))):
        host = draw(st.sampled_from(edges[:n_nominal]))
        u = host["source"]
        shape = draw(st.sampled_from(["direct", "via", "via2", "dead"]))
        entry = f"r{k}_in"
        host.setdefault("monitors", []).append({
            "id": f"m{k}", "failure_mode": draw(st.sampled_from(["drop", "slip", "toppled"])), "check": draw(constraint),
            "margin": draw(finite), "window": draw(st.integers(1, 10)), "recovery": entry})
        merge = lambda: f"n{draw(st.integers(0, n - 1))}"  # noqa: E731
        if shape == "direct":
            edges.append({"id": entry, "kind": "recovery", "source": u, "target": merge(), "cost": draw(cost), "actions": WAIT})
            continue
        nodes.append({"id": f"rec{k}", "kind": "recovery", "constraints": draw(st.lists(
            constraint.filter(lambda c: c.get("ref", 0) is not None), max_size=2))})
        edges.append({"id": entry, "kind": "recovery", "source": u, "target": f"rec{k}", "cost": draw(cost), "actions": WAIT})
        exits = {"via": 1, "via2": 2, "dead": 0}[shape]
        for x in range(exits):
            edges.append({"id": f"r{k}_out{x}", "kind": "recovery", "source": f"rec{k}", "target": merge(),
                          "cost": draw(cost), "actions": WAIT, "path_constraints": draw(st.lists(constraint, max_size=2))})
    return {"task": "random", "start": "n0", "goal": f"n{n - 1}", "nodes": nodes, "edges": edges}


@SETTINGS
@given(graphs())
def test_cost_to_go_is_a_shortest_path_cost(data):
    g = TaskGraph.from_data(data, VOCAB)
    ctg = cost_to_go(g)
    assert ctg[g.goal] == 0.0
    assert all(v >= 0.0 for v in ctg.values())
    assert all(math.isfinite(ctg[n.id]) for n in g.nodes if n.kind == "nominal")
    t = traversable(g)
    for u, v, w in t.edges(data="weight"):
        assert ctg[u] <= w + ctg[v] + 1e-9  # no edge beats it
    for u in t.nodes:
        if u != g.goal and math.isfinite(ctg[u]):  # and some edge attains it
            assert any(abs(ctg[u] - (w + ctg[v])) <= 1e-9 for _, v, w in t.out_edges(u, data="weight"))


@SETTINGS
@given(graphs())
def test_filter_never_keeps_a_branch_that_increases_cost_to_go(data):
    g = TaskGraph.from_data(data, VOCAB)
    r = forward_filter(g)
    out = r.graph.validate(VOCAB)
    before, after = cost_to_go(g), r.cost_to_go
    for b in r.kept:
        assert after[b.merge] <= after[b.context] + 1e-9
        assert b.edge in out.edge_map
    for b in r.rejected:
        assert b.edge not in out.edge_map
        assert b.merge is None or b.cost_merge is None or b.cost_merge > before[b.context]
    kinds = {n.id: n.kind for n in out.nodes}
    merges = {e.id for e in out.edges if e.kind == "recovery" and kinds[e.target] == "nominal"}
    assert merges == {b.edge for b in r.kept}  # every surviving branch was judged and kept
    # The nominal plan is untouched: same nodes, edges, costs; monitors stay (maybe detect-only).
    nominal = lambda gr: [(e.id, e.source, e.target, e.cost, [m.id for m in e.monitors])  # noqa: E731
                          for e in gr.edges if e.kind == "nominal"]
    assert nominal(out) == nominal(g)
    assert {k: v for k, v in after.items()} == {k: before[k] for k in after if kinds[k] == "nominal"} | {
        k: after[k] for k in after if kinds[k] == "recovery"}
    again = forward_filter(out)
    assert again.rejected == () and again.graph == out


@SETTINGS
@given(graphs())
def test_json_round_trip_identity(data):
    g = TaskGraph.from_data(data, VOCAB)
    text = g.to_json()
    assert TaskGraph.from_json(text, VOCAB) == g
    assert TaskGraph.from_json(text).to_json() == text
