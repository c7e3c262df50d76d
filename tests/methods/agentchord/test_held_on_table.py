"""A re-plan can find a hand closed on an object still standing on the table (a recovery given up after the
grasp, before the lift): the object is on the table and held, so the plan lifts it, where without `on_table` no
operator applied ("never achievable")."""

from __future__ import annotations

from kintsugi.methods.agentchord.composer import COMPOSER
from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.facts import observed_facts
from kintsugi.testing.pour_requests import composer_request


def _held_on_table():  # noqa: ANN202
    request = composer_request(bottle_held_by="right")
    bottle = request.objects[0].model_copy(update={"centroid": (0.40, -0.26, 0.1), "top_z": 0.2, "bottom_z": 0.0})
    return request.model_copy(update={"objects": [bottle, *request.objects[1:]]})


def test_a_held_object_standing_on_the_table_is_on_it_and_not_lifted() -> None:
    facts = observed_facts(_held_on_table(), TABLETOP_DOMAIN)
    assert {("holding", "right", "bottle"), ("on_table", "bottle")} <= facts
    assert ("lifted", "bottle") not in facts and ("released", "bottle") not in facts
    lifted = observed_facts(composer_request(bottle_held_by="right"), TABLETOP_DOMAIN)  # its bottom 0.2 m up
    assert ("lifted", "bottle") in lifted and ("on_table", "bottle") not in lifted


def test_the_plan_from_there_lifts_it_first() -> None:
    reply = COMPOSER.embedded(_held_on_table())
    first = reply.graph["edges"][0]
    assert first["id"].endswith("_lift") and [a["name"] for a in first["actions"]] == ["move_by_offset"]
