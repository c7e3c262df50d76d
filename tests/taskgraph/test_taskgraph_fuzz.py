"""Fuzz: >= 1,000 hostile or malformed graphs. Each is rejected with one GraphError or repaired by the
Eq. 8 filter (a backward or never-merging branch dropped); nothing else may escape."""

from __future__ import annotations

import copy
import json
import random
from collections import Counter

from kintsugi.taskgraph.base import GraphError
from kintsugi.taskgraph.forward import forward_filter
from kintsugi.taskgraph.model import TaskGraph
from tests.taskgraph_fixtures import VOCAB, act, pour_graph_data

N_CASES = 1200
JUNK = [None, True, 0, -1, 1e308, 10**100, "", "x" * 5000, [], {}, [1, 2], {"a": 1}, float("nan"), float("inf"),
        "NaN", "../../etc/passwd", "__class__", "n0 n1", {"kind": "python", "src": "__import__('os')"}]


def _paths(obj, prefix=()):
    """Every (container, key) in a JSON tree."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield obj, k
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield obj, i
            yield from _paths(v, prefix + (i,))


def _edge(d, rng, kind="nominal"):
    return rng.choice([e for e in d["edges"] if e.get("kind", "nominal") == kind])


def m_drop_field(d, rng):
    parent, key = rng.choice(list(_paths(d)))
    del parent[key]


def m_wrong_type(d, rng):
    parent, key = rng.choice(list(_paths(d)))
    parent[key] = copy.deepcopy(rng.choice(JUNK))


def m_junk_key(d, rng):
    parent, _ = rng.choice([p for p in _paths(d) if isinstance(p[0], dict)])
    parent[rng.choice(["exec", "code", "__proto__", "id2", "lambda"])] = "os.system('true')"


def m_cycle_no_exit(d, rng):
    a, b = f"c{rng.randrange(99)}a", f"c{rng.randrange(99)}b"
    src = rng.choice([n["id"] for n in d["nodes"] if n.get("kind", "nominal") == "nominal"])
    d["nodes"] += [{"id": a}, {"id": b}]
    d["edges"] += [{"id": f"{a}_in", "source": src, "target": a, "actions": [act("wait")]},
                   {"id": f"{a}_ab", "source": a, "target": b, "actions": [act("wait")]},
                   {"id": f"{a}_ba", "source": b, "target": a, "actions": [act("wait")]}]


def m_unknown_action(d, rng):
    e = rng.choice(d["edges"])
    e["actions"].append(act(rng.choice(["teleport", "grab", "Grasp", "exec", "rm -rf"]), arm="right"))


def m_unknown_object(d, rng):
    n = rng.choice([n for n in d["nodes"] if n.get("constraints")])
    c = n["constraints"][0]
    for key in ("object", "a", "point"):
        if key in c:
            c[key] = "mug" if key == "object" else {"entity": "mug"}
            return
    c["object"] = "mug"


def m_unknown_feature(d, rng):
    e = _edge(d, rng)
    e.setdefault("path_constraints", []).append(
        {"kind": "near", "a": {"entity": "cup", "feature": rng.choice(["bottom", "mass", "velocity"])},
         "b": {"entity": "bottle"}, "tol": 0.1})


def m_dangling(d, rng):
    rng.choice(d["edges"])[rng.choice(["source", "target"])] = "nowhere"


def m_duplicate(d, rng):
    which = rng.choice(["nodes", "edges"])
    d[which].append(copy.deepcopy(rng.choice(d[which])))


def m_nan(d, rng):
    e = _edge(d, rng)
    rng.choice([lambda: e.update(cost=float("nan")),
                lambda: e["actions"][0]["args"].update(z_offset=float("inf")),
                lambda: e.setdefault("path_constraints", []).append(
                    {"kind": "upright", "object": "bottle", "tol_deg": float("nan")}),
                lambda: d["nodes"][1]["constraints"][0].update(tol=float("-inf"))])()


def m_backward(d, rng):
    """A new recovery branch from a later context back to an earlier node: must be repaired away."""
    k = rng.randrange(10**6)
    e = rng.choice([e for e in d["edges"] if e["id"] in ("e_carry", "e_tilt", "e_restore")])
    e.setdefault("monitors", []).append({"id": f"mb{k}", "failure_mode": "slip", "recovery": f"rb{k}",
                                         "check": {"kind": "visibility", "object": "cup", "n_min": 20}})
    d["edges"].append({"id": f"rb{k}", "kind": "recovery", "source": e["source"], "target": "home",
                       "cost": rng.uniform(1, 50), "actions": [act("back", arm="right")]})


def m_unreachable_merge(d, rng):
    k = rng.randrange(10**6)
    e = _edge(d, rng)
    e.setdefault("monitors", []).append({"id": f"mu{k}", "failure_mode": "drop", "recovery": f"ru{k}",
                                         "check": {"kind": "detached", "arm": "right", "object": "bottle", "tol": 0.1}})
    d["nodes"].append({"id": f"limbo{k}", "kind": "recovery"})
    d["edges"].append({"id": f"ru{k}", "kind": "recovery", "source": e["source"], "target": f"limbo{k}",
                       "actions": [act("open_gripper", arm="right")]})


def m_huge(d, rng):
    rng.choice([
        lambda: d["nodes"].extend({"id": f"h{i}"} for i in range(300)),
        lambda: d["edges"].extend(d["edges"][0] | {"id": f"h{i}"} for i in range(1100)),
        lambda: d["edges"][0]["actions"].extend([act("wait")] * 40),
        lambda: d["nodes"][0].update(description="z" * 5000),
        lambda: d["edges"][0].update(cost=1e12),
    ])()


def m_deep(d, rng):
    depth = rng.choice([8, 50, 500])
    nested: object = 1
    for _ in range(depth):
        nested = {"x": nested} if rng.random() < 0.5 else [nested]
    target = rng.choice([lambda v: d["edges"][0]["actions"][0]["args"].update(deep=v),
                         lambda v: d["nodes"][0].update(gripper=v),
                         lambda v: d.update(task=v)])
    target(nested)


def m_missing_section(d, rng):
    del d[rng.choice(["start", "goal", "nodes"])]


MUTATIONS = [m_drop_field, m_wrong_type, m_junk_key, m_cycle_no_exit, m_unknown_action, m_unknown_object,
             m_unknown_feature, m_dangling, m_duplicate, m_nan, m_backward, m_unreachable_merge, m_huge, m_deep,
             m_missing_section]
REPAIRABLE = {m_backward, m_unreachable_merge}


def _text_case(rng, base_text):
    kind = rng.randrange(6)
    if kind == 0:
        return base_text[: rng.randrange(len(base_text))]  # truncated
    if kind == 1:
        return bytes(rng.randrange(256) for _ in range(rng.randrange(1, 200)))
    if kind == 2:
        return "[" * rng.choice([10, 1000, 200_000]) + "]" * 3
    if kind == 3:
        return json.dumps(rng.choice([None, 1, "graph", [], [pour_graph_data()]]))
    if kind == 4:
        i = rng.randrange(len(base_text))
        return base_text[:i] + rng.choice(["}", "{", '"', ",", "NaN", "\x00", "\\"]) + base_text[i + 1:]
    return base_text.replace('"start": "home"', '"start": "home", "start": "done"')  # duplicate key


def attempt(payload):
    """Load, check and filter; return the filter result, or the GraphError that rejected it."""
    try:
        g = TaskGraph.from_json(payload, VOCAB) if isinstance(payload, (str, bytes)) else TaskGraph.from_data(payload, VOCAB)
        return forward_filter(g)
    except GraphError as exc:
        return exc


def test_fuzz_hostile_graphs_rejected_or_repaired():
    rng = random.Random(20240611)
    base = pour_graph_data()
    base_text = json.dumps(base)
    outcomes: Counter[str] = Counter()
    for i in range(N_CASES):
        if i % 8 == 7:
            payload, applied = _text_case(rng, base_text), []
        else:
            data = json.loads(base_text)
            applied = rng.sample(MUTATIONS, rng.choice([1, 1, 1, 2, 3]))
            for m in applied:
                try:
                    m(data, rng)
                except (KeyError, IndexError, TypeError, AttributeError, ValueError):
                    pass  # an earlier mutation removed what this one edits; the graph is hostile anyway
            payload = data if rng.random() < 0.5 else json.dumps(data, allow_nan=True)
        result = attempt(payload)  # any exception other than GraphError fails the test here
        if isinstance(result, GraphError):
            assert str(result), "a rejection must say why"
            outcomes["rejected"] += 1
            continue
        # Accepted: the repaired graph is sound and no branch moves backward.
        result.graph.validate(VOCAB)
        assert forward_filter(result.graph).rejected == ()
        for b in result.kept:
            assert result.cost_to_go[b.merge] <= result.cost_to_go[b.context] + 1e-9
        if applied and set(applied) <= REPAIRABLE:
            assert result.rejected, f"{[m.__name__ for m in applied]} should have been repaired"
            outcomes["repaired"] += 1
        else:
            outcomes["accepted"] += 1
    assert sum(outcomes.values()) == N_CASES >= 1000
    assert outcomes["rejected"] > N_CASES // 2 and outcomes["repaired"] >= 50, outcomes


def test_each_hostile_family_fails_the_way_it_should():
    rng = random.Random(7)
    expect = {m_cycle_no_exit: "cycle with no exit", m_unknown_action: "unknown action", m_unknown_object: "mug",
              m_unknown_feature: "unknown feature", m_dangling: "is not a node", m_missing_section: "Field required"}
    for m, needle in expect.items():
        data = pour_graph_data()
        m(data, rng)
        result = attempt(json.dumps(data))
        assert isinstance(result, GraphError) and needle in str(result), (m.__name__, result)
    for m in (m_backward, m_unreachable_merge):
        data = pour_graph_data()
        m(data, rng)
        result = attempt(data)
        assert not isinstance(result, GraphError)
        assert any(b.edge is None or b.merge == "home" for b in result.rejected)
