"""Fuzz the composer's and the arranger's replies: 1,300 hostile or malformed replies, each parsed by the same
code an endpoint's reply goes through (JSON extraction, reply schema, role check). Each is rejected with one
ReasoningError that says why (and would be quoted back to the model for repair) or accepted/repaired into a
sound graph (backward or never-merging branches dropped by Eq. 8); nothing else may escape."""

from __future__ import annotations

import copy
import json
import random
from collections import Counter
from types import SimpleNamespace

import pytest

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.agentchord.arranger import check_arrangement, embedded_arrange
from kintsugi.methods.agentchord.composer import check_composition, embedded_compose
from kintsugi.reasoning.structured import StructuredClient
from kintsugi.methods.agentchord.types import ArrangerReply, ComposerReply
from tests.taskgraph_fixtures import arranger_request, composer_request, tabletop_vocab

N_COMPOSER = 650
N_ARRANGER = 650
VOCAB = tabletop_vocab()
JUNK = [None, True, 0, -1, 1e308, 10**100, "", "x" * 5000, [], {}, [1, 2], {"a": 1}, float("nan"), float("inf"),
        "NaN", "__class__", "n0 n1", {"kind": "python", "src": "__import__('os')"}]
REQ = composer_request()
COMPOSED = embedded_compose(REQ)
GRAPH = check_composition(COMPOSED, VOCAB)
ARRANGED = embedded_arrange(arranger_request(COMPOSED, REQ))


def _paths(obj):
    if isinstance(obj, dict):
        for k, v in list(obj.items()):
            yield obj, k
            yield from _paths(v)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield obj, i
            yield from _paths(v)


def act(name, **args):
    return {"name": name, "args": args}


# --- generic mutations (any reply) ------------------------------------------------------------------------

def m_drop_field(d, rng):
    parent, key = rng.choice(list(_paths(d)))
    del parent[key]


def m_wrong_type(d, rng):
    parent, key = rng.choice(list(_paths(d)))
    parent[key] = copy.deepcopy(rng.choice(JUNK))


def m_junk_key(d, rng):
    parent, _ = rng.choice([p for p in _paths(d) if isinstance(p[0], dict)])
    parent[rng.choice(["exec", "code", "__proto__", "id2", "lambda"])] = "os.system('true')"


def m_hostile_args(d, rng):
    """Arguments the robot's own action parser refuses (the vocabulary runs it on every call)."""
    edges = _all_edges(d)
    e = rng.choice(edges)
    a = rng.choice(e["actions"])
    a["args"].update(rng.choice([{"angle_deg": 1e9}, {"pre_grasp_offset": -1.0}, {"obj": "mug"}, {"arm": "middle"},
                                 {"dxyz": [0, 0]}, {"frame": "moon"}, {"action": "back"}, {"z_offset": "high"}]))


def m_unknown_action(d, rng):
    rng.choice(_all_edges(d))["actions"].append(act(rng.choice(["teleport", "Grasp", "exec", "rm -rf", "wait"]),
                                                    arm="right"))


def m_nan(d, rng):
    e = rng.choice(_all_edges(d))
    rng.choice([lambda: e.update(cost=float("nan")),
                lambda: e["actions"][0]["args"].update(x=float("inf")),
                lambda: e.setdefault("path_constraints", []).append(
                    {"kind": "upright", "object": "bottle", "tol_deg": float("nan")}),
                lambda: e.setdefault("path_constraints", []).append(
                    {"kind": "near", "a": {"entity": "cup"}, "b": {"entity": "right"}, "tol": float("-inf")})])()


def _all_edges(d):
    if "graph" in d:
        return d["graph"]["edges"]
    return [e for p in d["proposals"] for e in p["edges"]]


# --- composer-specific ----------------------------------------------------------------------------------

def c_cycle_no_exit(d, rng):
    g = d["graph"]
    src = rng.choice([n["id"] for n in g["nodes"]])
    g["nodes"] += [{"id": "ca"}, {"id": "cb"}]
    g["edges"] += [{"id": "ca_in", "source": src, "target": "ca", "actions": [act("back", arm="right")]},
                   {"id": "ca_ab", "source": "ca", "target": "cb", "actions": [act("back", arm="right")]},
                   {"id": "ca_ba", "source": "cb", "target": "ca", "actions": [act("back", arm="right")]}]


def c_recovery_inside(d, rng):
    rng.choice(d["graph"]["nodes"] + d["graph"]["edges"])["kind"] = "recovery"


def c_dangling(d, rng):
    rng.choice(d["graph"]["edges"])[rng.choice(["source", "target"])] = "nowhere"


def c_stray_facts(d, rng):
    d[rng.choice(["node_facts", "edge_operators"])]["ghost"] = ["holding(right, bottle)"] if rng.random() < .5 else "x"


def c_unknown_object(d, rng):
    n = rng.choice([n for n in d["graph"]["nodes"] if n.get("constraints")])
    c = n["constraints"][0]
    for key in ("object", "a", "point"):
        if key in c:
            c[key] = "mug" if key == "object" else {"entity": "mug"}
            return
    c["arm"] = "third"


def c_goal_is_start(d, rng):
    d["graph"]["goal"] = d["graph"]["start"]


COMPOSER_MUTATIONS = [m_drop_field, m_wrong_type, m_junk_key, m_hostile_args, m_unknown_action, m_nan,
                      c_cycle_no_exit, c_recovery_inside, c_dangling, c_stray_facts, c_unknown_object, c_goal_is_start]


# --- arranger-specific ----------------------------------------------------------------------------------

def a_backward(d, rng):
    """A branch that sends the robot back to the start from a later edge: Eq. 8 must drop it (repair)."""
    p = rng.choice([p for p in d["proposals"] if p["edge"] != "e1_grasp"])
    p["nodes"], first = [], p["edges"][0]
    first["target"] = "start"
    p["edges"] = [first]


def a_unreachable_merge(d, rng):
    p = rng.choice(d["proposals"])
    p["nodes"].append({"id": "limbo", "description": "nowhere"})
    p["edges"][0]["target"] = "limbo"
    p["edges"] = p["edges"][:1]


def a_recovery_cycle(d, rng):
    p = rng.choice([p for p in d["proposals"] if len(p["nodes"]) >= 2])
    p["edges"].append({"id": "loop", "source": p["nodes"][1]["id"], "target": p["nodes"][0]["id"],
                       "actions": [act("back", arm="right")]})


def a_unknown_edge(d, rng):
    rng.choice(d["proposals"])["edge"] = rng.choice(["e9_fly", "re.e1_grasp.drop.right.1", ""])


def a_wrong_context(d, rng):
    p = rng.choice(d["proposals"])
    p["edges"][0]["source"] = rng.choice(["s6_place", "start", "s2_lift"])


def a_bad_monitor(d, rng):
    m = rng.choice(d["proposals"])["monitor"]
    m.update(rng.choice([{"window": 0}, {"margin": -1.0}, {"margin": float("nan")}, {"recovery": "nothing"},
                         {"check": {"kind": "eval", "src": "1"}}, {"check": {"kind": "not_grasped", "arm": "right"}},
                         {"id": "m.e1_grasp.missed_grasp.right"}, {"failure_mode": "1nvalid name"}]))


def a_monitor_on_recovery(d, rng):
    p = rng.choice(d["proposals"])
    p["edges"][-1]["monitors"] = [copy.deepcopy(p["monitor"]) | {"id": "inner"}]


def a_flood(d, rng):
    p = d["proposals"][0]
    rng.choice([lambda: d["proposals"].extend(copy.deepcopy(p) for _ in range(300)),
                lambda: p["nodes"].extend({"id": f"f{i}"} for i in range(20)),
                lambda: p["edges"][0]["actions"].extend([act("back", arm="right")] * 40)])()


ARRANGER_MUTATIONS = [m_drop_field, m_wrong_type, m_junk_key, m_hostile_args, m_unknown_action, m_nan, a_backward,
                      a_unreachable_merge, a_recovery_cycle, a_unknown_edge, a_wrong_context, a_bad_monitor,
                      a_monitor_on_recovery, a_flood]
REPAIRABLE = {a_backward, a_unreachable_merge, m_drop_field}
"""m_drop_field may delete one edge of a recovery chain: its recovery node then never merges, and Eq. 8's
filter drops that branch (a repair, as for an unreachable merge)."""


def _text(rng, base: str) -> str:
    kind = rng.randrange(5)
    if kind == 0:
        return base[: rng.randrange(len(base))]
    if kind == 1:
        return "[" * rng.choice([10, 1000, 100_000]) + "]"
    if kind == 2:
        return json.dumps(rng.choice([None, 1, "graph", [], [base]]))
    if kind == 3:
        i = rng.randrange(len(base))
        return base[:i] + rng.choice(["}", "{", '"', ",", "NaN", "\x00", "\\"]) + base[i + 1:]
    return "Sure! Here is the graph:\n```json\n" + base + "\n```"


def _replies(rng, base_reply, mutations, n):
    base = json.loads(base_reply.model_dump_json())
    text = json.dumps(base)
    for i in range(n):
        if i % 9 == 8:
            yield _text(rng, text), []
            continue
        data = copy.deepcopy(base)
        applied = rng.sample(mutations, rng.choice([1, 1, 1, 2, 3]))
        for m in applied:
            try:
                m(data, rng)
            except (KeyError, IndexError, TypeError, AttributeError, ValueError):
                pass  # an earlier mutation removed what this one edits; the reply is hostile anyway
        yield json.dumps(data, allow_nan=True), applied


def _parse(text: str, reply_type, check):
    """What an endpoint's reply goes through: JSON extraction, the reply's schema, then the role's check."""
    message = SimpleNamespace(content=text, tool_calls=None, refusal=None)
    return StructuredClient._parse(message, reply_type, check, None)


def test_hostile_composer_replies_are_rejected_clearly() -> None:
    rng = random.Random(8)
    outcomes: Counter[str] = Counter()
    for text, _ in _replies(rng, COMPOSED, COMPOSER_MUTATIONS, N_COMPOSER):
        try:
            _parse(text, ComposerReply, lambda r: (check_composition(r, VOCAB), r)[1])
        except ReasoningError as exc:
            assert str(exc) and len(str(exc)) < 2000
            outcomes["rejected"] += 1
        else:
            outcomes["accepted"] += 1
    assert sum(outcomes.values()) == N_COMPOSER
    assert outcomes["rejected"] > 0.8 * N_COMPOSER


@pytest.mark.slow
def test_hostile_arranger_replies_are_rejected_or_repaired() -> None:
    rng = random.Random(12)
    outcomes: Counter[str] = Counter()
    for text, applied in _replies(rng, ARRANGED, ARRANGER_MUTATIONS, N_ARRANGER):
        box = {}

        def check(reply: ArrangerReply) -> ArrangerReply:
            box["result"] = check_arrangement(reply, GRAPH, VOCAB)
            return reply

        try:
            _parse(text, ArrangerReply, check)
        except ReasoningError as exc:
            assert str(exc) and len(str(exc)) < 2000
            outcomes["rejected"] += 1
            continue
        result = box["result"]
        for b in result.kept:  # whatever survived moves forward (Eq. 8)
            assert b.cost_merge is not None and b.cost_merge <= b.cost_context + 1e-9
        if result.rejected:
            assert set(applied) & REPAIRABLE, f"branches dropped without a repairable mutation: {applied}"
            outcomes["repaired"] += 1
        else:
            outcomes["accepted"] += 1
    assert sum(outcomes.values()) == N_ARRANGER
    assert outcomes["rejected"] > 0.5 * N_ARRANGER and outcomes["repaired"] >= 20, outcomes
