"""Composer and arranger roles: embedded planning from goal predicates, the knowledge-base arranger with Eq. 8,
both recorded in the transcript, and the openai path (local fake server) with one repair round."""

from __future__ import annotations

import json

import pytest

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.agentchord.arranger import check_arrangement, embedded_arrange
from kintsugi.methods.agentchord.composer import check_composition, embedded_compose
from kintsugi.methods.agentchord.symbolic import PlanningError
from tests.taskgraph_fixtures import arranger_request, composer_request, tabletop_vocab

POUR_PLAN = ["grasp(right, bottle)", "lift(right, bottle)", "carry_over(right, bottle, cup)", "pour(right, bottle, cup)",
             "restore(right, bottle)", "place(right, bottle)"]


def _compose(**kw):
    req = composer_request(**kw)
    reply = embedded_compose(req)
    return req, reply, check_composition(reply, tabletop_vocab())


def test_composer_plans_the_pour_from_its_goal_predicates() -> None:
    _, reply, graph = _compose()
    assert list(reply.edge_operators.values()) == POUR_PLAN
    assert graph.start == "start" and graph.goal == "s6_place"
    carry = graph.edge("e3_carry_over").actions[0]
    assert carry.name == "move_to_obj" and carry.args["offset"] == [0.0, -0.1, 0.14]
    place = graph.edge("e6_place").actions[0]
    assert (place.args["x"], place.args["y"]) == (0.4, -0.26)  # where perception first saw the bottle
    kinds = {n.id: [c.kind for c in n.constraints] for n in graph.nodes}
    assert kinds["s1_grasp"] == ["detached", "touching"] and kinds["s4_pour"] == ["tilted"]
    assert graph.node("s1_grasp").gripper == {"right": "closed"} and graph.node("s6_place").gripper == {"right": "open"}


def test_composer_follows_the_goal_not_a_script() -> None:
    _, reply, _ = _compose(goal=["poured(bottle, cup)"])
    assert list(reply.edge_operators.values()) == POUR_PLAN[:4]
    _, reply, _ = _compose(goal=["holding(right, bottle)"])
    assert list(reply.edge_operators.values()) == ["grasp(right, bottle)"]
    _, reply, _ = _compose(bottle_held_by="right")  # already in hand, off the table: no grasp, no lift
    assert list(reply.edge_operators.values())[0] == "carry_over(right, bottle, cup)"


def test_composer_uses_the_arm_the_instruction_names() -> None:
    _, reply, graph = _compose(task="Pour from the bottle into the cup with the left arm.")
    assert all(op.startswith(("grasp(left", "lift(left", "carry_over(left", "pour(left", "restore(left", "place(left"))
               for op in reply.edge_operators.values())
    assert graph.edge("e4_pour").actions[0].args["angle_deg"] == 100.0  # mirrored for the left arm


@pytest.mark.parametrize("goal, message", [
    (["spilled(bottle)"], "unknown predicate 'spilled'"),
    (["poured(bottle)"], "poured takes 2 argument(s)"),
    (["poured(bottle, bottle)"], "cannot be reached"),
    (["upright(cup)"], "goal already holds"),
])
def test_composer_refuses_goals_it_cannot_plan(goal: list[str], message: str) -> None:
    with pytest.raises(PlanningError, match=message.replace("(", r"\(").replace(")", r"\)")):
        embedded_compose(composer_request(goal=goal))


def test_a_fallen_bottle_has_no_side_grasp_plan() -> None:
    with pytest.raises(PlanningError, match=r"never achievable: poured\(bottle, cup\), upright\(bottle\)"):
        embedded_compose(composer_request(bottle_upright=False))


def test_arranger_adds_forward_branches_from_its_knowledge_base() -> None:
    req, reply, graph = _compose()
    arranged = embedded_arrange(arranger_request(reply, req))
    result = check_arrangement(arranged, graph)
    result.graph.validate(tabletop_vocab())
    assert not result.rejected and len(result.kept) == 24
    modes = {(e.id, m.failure_mode) for e, m in result.graph.monitors()}
    assert ("e1_grasp", "missed_grasp") in modes and ("e3_carry_over", "drop") in modes
    # A knocked-over bottle is stood back up before the side grasp (the stand_up operator).
    stand = result.graph.edge("re.e1_grasp.toppled.right.lying.1")
    assert [a.name for a in stand.actions] == ["grasp", "move_by_offset", "rotate_eef", "place"]
    # A dropped bottle may land standing or lying: a hub branches on what perception sees once it is at rest.
    hub = result.graph.edge("re.e3_carry_over.drop.right.0").target
    guards = {e.id.split(".")[-2]: [c.kind for c in e.guard] for e in result.graph.out_edges(hub)}
    assert guards == {"standing": ["upright"], "lying": ["tilted"]}
    place = next(m for e, m in result.graph.monitors() if e.id == "e6_place" and m.failure_mode == "drop")
    assert place.check.while_closed  # the place lets go on purpose: watched until the hand opens
    merges = {}
    for e, m in result.graph.monitors():  # each recovery merges at the failed edge's target or later (forward)
        branch = next(b for b in result.kept if m.id in b.monitors)
        assert branch.context == e.source and branch.cost_merge <= branch.cost_context
        merges[(e.id, m.failure_mode)] = branch.merge
    assert merges[("e3_carry_over", "drop")] == "s3_carry_over" and merges[("e1_grasp", "missed_grasp")] == "s1_grasp"
    # a drop while turning back (or while placing) leaves every goal fact true if the bottle lands upright:
    # release, merge at the goal; if it lands lying, it is stood up, which also reaches the goal
    assert merges[("e5_restore", "drop")] == "s6_place" and merges[("e6_place", "drop")] == "s6_place"
    entry = result.graph.edge(next(m.recovery for e, m in result.graph.monitors()
                                   if e.id == "e5_restore" and m.failure_mode == "drop"))
    branches = {x.guard[0].kind: x for x in result.graph.out_edges(entry.target)}
    assert [a.name for a in branches["upright"].actions] == ["open_gripper"]
    assert branches["upright"].target == branches["tilted"].target == "s6_place"
    pour_drop = next(m for e, m in result.graph.monitors() if e.id == "e4_pour" and m.failure_mode == "drop")
    hub = result.graph.edge(pour_drop.recovery).target
    chain = [next(x for x in result.graph.out_edges(hub) if x.guard[0].kind == "upright")]
    while result.graph.node(chain[-1].target).kind == "recovery":
        chain.append(next(x for x in result.graph.edges if x.source == chain[-1].target))
    assert [x.actions[0].name for x in chain] == ["grasp", "move_by_offset", "move_to_obj", "rotate_eef"]
    assert pour_drop.check.kind == "touching" and pour_drop.window == 3


def test_arranger_needs_the_composers_facts() -> None:
    req, reply, _ = _compose()
    bare = arranger_request(reply.model_copy(update={"node_facts": {}}), req)
    with pytest.raises(PlanningError, match="needs each node's facts"):
        embedded_arrange(bare)


def test_both_roles_are_recorded_on_the_embedded_backend() -> None:
    from kintsugi.reasoning import make_reasoner
    from kintsugi.methods.agentchord.arranger import ask_arrange
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.methods.agentchord.composer import ask_compose
    from kintsugi.core.record import ReasonerSettings

    rec = RecordingReasoner(make_reasoner(ReasonerSettings()))
    req = composer_request()
    graph, reply = ask_compose(rec, req, tabletop_vocab())
    result, _ = ask_arrange(rec, arranger_request(reply, req), graph, tabletop_vocab())
    assert [r.role for r in rec.records] == ["composer", "arranger"]
    assert all(r.backend == "embedded" and r.error is None for r in rec.records)
    assert len(result.kept) == 24


def test_an_unplannable_goal_is_a_recorded_reasoning_error() -> None:
    from kintsugi.reasoning import make_reasoner
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.methods.agentchord.composer import ask_compose
    from kintsugi.core.record import ReasonerSettings

    rec = RecordingReasoner(make_reasoner(ReasonerSettings()))
    with pytest.raises(ReasoningError):
        ask_compose(rec, composer_request(goal=["spilled(bottle)"]), tabletop_vocab())
    assert rec.records[0].role == "composer" and "unknown predicate 'spilled'" in rec.records[0].error


def test_roles_over_the_openai_protocol_repair_a_bad_graph() -> None:
    from kintsugi.methods.agentchord.arranger import ask_arrange
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.methods.agentchord.composer import ask_compose
    from kintsugi.reasoning.openai_backend import OpenAIReasoner
    from tests.fake_openai_server import FakeOpenAIServer, content

    req = composer_request().model_copy(update={"images_png": {"top": b"\x89PNG\r\n\x1a\nfake"}})
    good = embedded_compose(req)
    bad = json.loads(good.model_dump_json())
    bad["graph"]["edges"][0]["actions"][0]["name"] = "teleport"
    arranged = embedded_arrange(arranger_request(good, req))
    looped = json.loads(arranged.model_dump_json())
    p = next(p for p in looped["proposals"] if len(p["nodes"]) >= 2)
    p["edges"].append({"id": "loop", "source": p["nodes"][1]["id"], "target": p["nodes"][0]["id"], "kind": "recovery",
                       "actions": [{"name": "back", "args": {"arm": "right"}}]})
    with FakeOpenAIServer() as server:
        server.push(content(bad), content(json.loads(good.model_dump_json())), content(looped),
                    content(json.loads(arranged.model_dump_json())))
        rec = RecordingReasoner(OpenAIReasoner(model="fake-vlm", base_url=server.base_url,
                                               api_key_env="KINTSUGI_TEST_NO_SUCH_KEY"))
        graph, _ = ask_compose(rec, req, tabletop_vocab())
        result, _ = ask_arrange(rec, arranger_request(good, req), graph, tabletop_vocab())
        sent = [json.dumps(r["messages"]) for r in server.requests]
    assert graph.goal == "s6_place" and len(result.kept) == 24
    assert [(r.role, r.attempts) for r in rec.records] == [("composer", 2), ("arranger", 2)]
    assert "Role: composer" in sent[0] and "planning module" in sent[0] and "image_url" in sent[0]
    assert "unknown action 'teleport'" in sent[1]
    assert "Role: arranger" in sent[2] and "form a cycle" in sent[3]
