"""System B's reasoner requests, hand-built without a simulator: what perception and the arms would report for
a pour layout, and AgentChord's composer and arranger requests for it."""

from __future__ import annotations

from typing import Any


def seen_scene(bottle_held_by: str | None = None, bottle_upright: bool = True):
    """What perception and the arms would report for a pour layout: bottle at (0.40, -0.26), cup at (0.46, 0)."""
    from kintsugi.methods.agentchord.types import SeenArm, SeenObject

    bottom = 0.2 if bottle_held_by else 0.0
    objects = [
        SeenObject(name="bottle", visible=True, centroid=(0.40, -0.26, bottom + 0.1), top_z=bottom + 0.2,
                   bottom_z=bottom, tilt_deg=0.5 if bottle_upright else 88.0, upright=bottle_upright,
                   extent=(0.2, 0.06, 0.06)),
        SeenObject(name="cup", visible=True, centroid=(0.46, 0.0, 0.045), top_z=0.09, bottom_z=0.0, tilt_deg=0.3,
                   upright=True, extent=(0.09, 0.09, 0.09)),
    ]
    arms = [SeenArm(name=a, tcp_pos=(0.3, 0.3 if a == "left" else -0.3, 0.35), gripper_opening_m=0.1,
                    gripper_closed=False, holding=["bottle"] if a == bottle_held_by else []) for a in ("left", "right")]
    return objects, arms


POUR_TEXT = "Pour water from the bottle into the cup using the right arm, then put the bottle back upright on the table."
POUR_GOAL = ["poured(bottle, cup)", "upright(bottle)", "on_table(bottle)", "released(bottle)", "upright(cup)"]


def composer_request(task: str = POUR_TEXT, goal: list[str] | None = None, **scene: Any):
    from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
    from kintsugi.methods.agentchord.types import ComposerRequest

    objects, arms = seen_scene(**scene)
    return ComposerRequest(task=task, goal=goal or POUR_GOAL, objects=objects, arms=arms, domain=TABLETOP_DOMAIN)


def arranger_request(composer_reply, request):
    """The arranger's request for a composer's reply to `request`."""
    from kintsugi.methods.agentchord.types import ArrangerRequest

    return ArrangerRequest(task=request.task, graph=composer_reply.graph, node_facts=composer_reply.node_facts,
                           edge_operators=composer_reply.edge_operators, objects=request.objects, arms=request.arms,
                           domain=request.domain)
