"""Task graph model: JSON round trip, schema, and one GraphError naming each kind of bad element."""

from __future__ import annotations

import copy
import json

import pytest

from kintsugi.core.errors import KintsugiError
from kintsugi.taskgraph.augment import RecoveryProposal, augment, parse_proposals
from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.forward import cost_to_go, next_edge
from kintsugi.taskgraph.model import MAX_NODES, TaskGraph
from kintsugi.taskgraph.vocabulary import Vocabulary
from tests.taskgraph_fixtures import VOCAB, act, pour_graph, pour_graph_data


def test_round_trip_is_identity():
    g = pour_graph()
    text = g.to_json()
    again = TaskGraph.from_json(text, VOCAB)
    assert again == g
    assert again.to_json() == text
    assert TaskGraph.from_json(g.to_json(indent=2)) == g


def test_networkx_view_and_lookups():
    g = pour_graph()
    assert g.nx.number_of_nodes() == len(g.nodes) and g.nx.number_of_edges() == len(g.edges)
    assert g.nx.edges["home", "home", "r_retry"]["weight"] == 20
    assert [e.id for e in g.out_edges("grasped", "recovery")] == ["r_pick", "r_reset"]
    assert [m.id for _, m in g.monitors()] == ["m_miss", "m_drop", "m_cup", "m_vis"]
    with pytest.raises(GraphError, match="no node 'nope'"):
        g.node("nope")


def test_json_schema_for_structured_output():
    schema = json.dumps(TaskGraph.model_json_schema())
    for kind in ("drift", "upright", "not_grasped", "detached", "visibility", "misaligned", "in_region"):
        assert f'"{kind}"' in schema


def test_next_edge_follows_cheapest_nominal_route():
    data = pour_graph_data()
    data["edges"].append({"id": "e_short", "source": "grasped", "target": "poured", "cost": 50,
                          "actions": [act("rotate_eef", arm="right", angle_deg=90)]})
    g = TaskGraph.from_data(data, VOCAB)
    assert next_edge(g, "grasped").id == "e_short"  # 50 + 30 < 60 + 30 + 30
    assert next_edge(g, "home").id == "e_grasp"  # never a failure-only recovery edge
    assert next_edge(g, "regrasp").id == "r_merge"
    assert next_edge(g, "done") is None
    assert cost_to_go(g)["grasped"] == 80


def mutate(fn):
    data = pour_graph_data()
    fn(data)
    return data


def edge(data, eid):
    return next(e for e in data["edges"] if e["id"] == eid)


def node(data, nid):
    return next(n for n in data["nodes"] if n["id"] == nid)


BAD = {
    "unknown action": (lambda d: edge(d, "e_grasp")["actions"].__setitem__(0, act("grab", arm="right")),
                       "edge 'e_grasp' action 0: unknown action 'grab'"),
    "bad action args": (lambda d: edge(d, "e_grasp")["actions"][0]["args"].update(object="mug"),
                        "edge 'e_grasp' action 0: action 'grasp' arguments rejected"),
    "callable validator": (lambda d: edge(d, "e_tilt")["actions"][0]["args"].update(angle_deg=500),
                           "edge 'e_tilt' action 0: action 'rotate_eef' arguments rejected: ValueError: angle_deg"),
    "unknown object": (lambda d: node(d, "done")["constraints"][0].update(object="mug"), "unknown object 'mug'"),
    "unknown feature": (lambda d: node(d, "over_cup")["constraints"][0]["b"].update(feature="bottom"),
                        "node 'over_cup' constraint 0 (above): unknown feature 'bottom'"),
    "arm feature": (lambda d: node(d, "grasped")["constraints"][0]["a"].update(feature="centroid"),
                    "arm 'right' has no feature 'centroid'"),
    "unknown arm": (lambda d: node(d, "home")["gripper"].update(middle="open"), "unknown arm 'middle'"),
    "monitor object": (lambda d: edge(d, "e_tilt")["monitors"][0]["check"].update(object="mug"),
                       "edge 'e_tilt' monitor 'm_vis' (visibility): unknown object 'mug'"),
    "dangling": (lambda d: edge(d, "e_tilt").update(target="nowhere"), "edge 'e_tilt': target 'nowhere' is not a node"),
    "no path": (lambda d: d["edges"].remove(edge(d, "e_restore")), "no nominal path from start 'home' to goal 'done'"),
    "cycle without exit": (lambda d: (d["nodes"].extend([{"id": "x"}, {"id": "y"}]), d["edges"].extend([
        {"id": "c1", "source": "over_cup", "target": "x", "actions": [act("wait")]},
        {"id": "c2", "source": "x", "target": "y", "actions": [act("wait")]},
        {"id": "c3", "source": "y", "target": "x", "actions": [act("wait")]}])), "nominal cycle with no exit through 'x', 'y'"),
    "dead end": (lambda d: (d["nodes"].append({"id": "x"}), d["edges"].append(
        {"id": "c1", "source": "over_cup", "target": "x", "actions": [act("wait")]})), "nominal node 'x' is a dead end"),
    "unreachable node": (lambda d: d["nodes"].append({"id": "island"}), "nominal node 'island' cannot be reached"),
    "nan cost": (lambda d: edge(d, "e_tilt").update(cost=float("nan")), "edges[2] 'e_tilt'.cost"),
    "inf arg": (lambda d: edge(d, "e_grasp")["actions"][0]["args"].update(x=float("inf")), "finite"),
    "nan constraint": (lambda d: node(d, "done")["constraints"][0].update(tol_deg=float("nan")), "nodes[4] 'done'.constraints[0]"),
    "bool cost": (lambda d: edge(d, "e_tilt").update(cost=True), "cost"),
    "zero cost": (lambda d: edge(d, "e_tilt").update(cost=0), "greater than 0"),
    "duplicate node": (lambda d: d["nodes"].append({"id": "poured"}), "duplicated node id 'poured'"),
    "duplicate edge": (lambda d: d["edges"].append(dict(edge(d, "e_tilt"))), "duplicated edge id 'e_tilt'"),
    "duplicate monitor": (lambda d: edge(d, "e_tilt")["monitors"][0].update(id="m_drop"), "duplicated monitor id 'm_drop'"),
    "monitor on recovery edge": (lambda d: edge(d, "r_merge").update(monitors=[edge(d, "e_tilt")["monitors"].pop()]),
                                 "recovery edge 'r_merge' carries monitors"),
    "recovery from wrong context": (lambda d: edge(d, "e_tilt")["monitors"][0].update(recovery="r_pick"),
                                    "failure context is 'over_cup'"),
    "recovery to nominal edge": (lambda d: edge(d, "e_tilt")["monitors"][0].update(recovery="e_restore"),
                                 "'e_restore' is a nominal edge"),
    "missing recovery edge": (lambda d: edge(d, "e_tilt")["monitors"][0].update(recovery="r_gone"), "'r_gone' does not exist"),
    "untriggered recovery": (lambda d: edge(d, "e_grasp")["monitors"].clear(), "recovery edge 'r_retry' leaves nominal node 'home' but no monitor"),
    "orphan recovery node": (lambda d: d["nodes"].append({"id": "lost", "kind": "recovery"}), "recovery node 'lost' is never entered"),
    "two contexts": (lambda d: (edge(d, "e_grasp")["monitors"].append(
        {"id": "m2", "failure_mode": "drop", "check": {"kind": "visibility", "object": "bottle", "n_min": 5}, "recovery": "r2"}),
        d["edges"].append({"id": "r2", "kind": "recovery", "source": "home", "target": "regrasp", "actions": [act("wait")]})),
        "recovery node 'regrasp' is entered from several failure contexts"),
    "recovery cycle": (lambda d: (d["nodes"].append({"id": "r_x", "kind": "recovery"}), d["edges"].extend([
        {"id": "q1", "kind": "recovery", "source": "regrasp", "target": "r_x", "actions": [act("wait")]},
        {"id": "q2", "kind": "recovery", "source": "r_x", "target": "regrasp", "actions": [act("wait")]}])),
        "recovery nodes form a cycle"),
    "nominal edge into recovery node": (lambda d: edge(d, "e_tilt").update(target="regrasp"),
                                        "nominal edge 'e_tilt': target 'regrasp' is a recovery node"),
    "recovery start": (lambda d: d.update(start="regrasp"), "start 'regrasp' must be a nominal node"),
    "start is goal": (lambda d: d.update(start="done"), "start and goal are the same node"),
    "unbound node drift": (lambda d: node(d, "done")["constraints"].append(
        {"kind": "drift", "point": {"entity": "cup"}, "tol": 0.02}), "node 'done' constraint 1 (drift) has no reference"),
    "missing field": (lambda d: edge(d, "e_tilt").pop("actions"), "edges[2] 'e_tilt'.actions: Field required"),
    "no actions": (lambda d: edge(d, "e_tilt").update(actions=[]), "edges[2] 'e_tilt'.actions"),
    "extra key": (lambda d: edge(d, "e_tilt").update(code="import os"), "edges[2] 'e_tilt'.code: Extra inputs"),
    "wrong type": (lambda d: d.update(nodes="home,done"), "nodes"),
    "wrong version": (lambda d: d.update(version=2), "version"),
    "bad id": (lambda d: node(d, "poured").update(id="has space"), "nodes[3]"),
    "too many nodes": (lambda d: d["nodes"].extend({"id": f"n{i}"} for i in range(MAX_NODES + 1)), "nodes"),
    "deep args": (lambda d: edge(d, "e_grasp")["actions"][0]["args"].update(
        x=json.loads("[" * 20 + "]" * 20)), "nested deeper"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_graph_is_one_graph_error_naming_it(case):
    fn, needle = BAD[case]
    data = mutate(fn)
    with pytest.raises(GraphError) as exc:
        TaskGraph.from_json(json.dumps(data), VOCAB)
    assert needle in str(exc.value), str(exc.value)
    assert isinstance(exc.value, KintsugiError)


@pytest.mark.parametrize("text", ["", "{", "[]", "null", "42", '"graph"', b"\xff\xfe", "[" * 100_000, "x" * 3_000_000])
def test_not_a_graph(text):
    with pytest.raises(GraphError):
        TaskGraph.from_json(text)


def test_not_text():
    with pytest.raises(GraphError, match="must be JSON text"):
        TaskGraph.from_json(123)  # type: ignore[arg-type]


def test_vocabulary_rejects_name_clash():
    with pytest.raises(GraphError, match="both as object and arm"):
        Vocabulary(actions={}, objects=frozenset({"left"}))


def nominal_data():
    data = pour_graph_data()
    data["nodes"] = [n for n in data["nodes"] if n.get("kind") != "recovery"]
    data["edges"] = [dict(e, monitors=[]) for e in data["edges"] if e.get("kind") != "recovery"]
    return data


def test_augment_rebuilds_the_hand_made_graph():
    full = pour_graph_data()
    base = TaskGraph.from_data(nominal_data(), VOCAB)
    mons = {m["id"]: (e["id"], m) for e in full["edges"] for m in e.get("monitors", [])}
    rec_edges = {e["id"]: e for e in full["edges"] if e.get("kind") == "recovery"}
    rec_nodes = {n["id"]: n for n in full["nodes"] if n.get("kind") == "recovery"}
    branch = {"m_miss": ([], ["r_retry"]), "m_drop": (["regrasp"], ["r_pick", "r_merge"]),
              "m_cup": (["reset"], ["r_reset", "r_home"]), "m_vis": ([], [])}
    proposals = parse_proposals([
        {"edge": mons[m][0], "monitor": mons[m][1], "nodes": [dict(rec_nodes[n], kind="nominal") for n in ns],
         "edges": [rec_edges[e] for e in es]} for m, (ns, es) in branch.items()
    ])
    g = augment(base, proposals)
    assert g == pour_graph()


def test_augment_errors():
    base = TaskGraph.from_data(nominal_data(), VOCAB)
    mon = {"id": "m", "failure_mode": "drop", "check": {"kind": "visibility", "object": "cup", "n_min": 3}}
    with pytest.raises(GraphError, match="no such nominal edge"):
        augment(base, [RecoveryProposal(edge="e_nope", monitor=mon)])
    with pytest.raises(GraphError, match="monitors"):
        augment(base, [RecoveryProposal(edge="e_tilt", monitor=dict(mon, id=f"m{i}")) for i in range(17)])
    with pytest.raises(GraphError, match="recovery proposal 0 rejected: monitor.check"):
        parse_proposals([{"edge": "e_tilt", "monitor": dict(mon, check={"kind": "eval", "src": "1"})}])
    with pytest.raises(GraphError, match="must be a JSON list"):
        parse_proposals({"edge": "e_tilt"})


def test_validate_uses_deep_copies_safely():
    data = pour_graph_data()
    before = copy.deepcopy(data)
    TaskGraph.from_data(data, VOCAB)
    assert data == before


def test_copy_is_checked_and_drops_cached_views():
    g = pour_graph()
    assert g.nx.edges["over_cup", "poured", "e_tilt"]["weight"] == 30
    edges = tuple(e.model_copy(update={"cost": 7.0}) if e.id == "e_tilt" else e for e in g.edges)
    cheaper = g.model_copy(update={"edges": edges})
    assert cheaper.nx.edges["over_cup", "poured", "e_tilt"]["weight"] == 7
    assert g.nx.edges["over_cup", "poured", "e_tilt"]["weight"] == 30
    assert cheaper == TaskGraph.from_json(cheaper.to_json())
    with pytest.raises(GraphError, match="recovery edge 'r_pick' does not exist"):
        g.model_copy(update={"edges": tuple(e for e in g.edges if e.id != "r_pick")})
