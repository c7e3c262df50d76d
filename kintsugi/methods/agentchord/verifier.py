"""The verify role (Inner Monologue, DoReMi, Code-as-Monitor baselines): does a sub-goal hold now?

The embedded verifier reads the request's perceived features and evaluates the sub-goal's constraint
templates on them (what a VLM answers by looking): success when none is violated by more than a few
millimetres or degrees; a constraint it cannot
evaluate (an object not seen) counts as not verified. `ask_verify` runs the role on any backend.
"""

from __future__ import annotations

from typing import Any

from pydantic import TypeAdapter, ValidationError

from kintsugi.methods.agentchord.facts import looks_upright
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask
from kintsugi.methods.agentchord.types import VerifyReply, VerifyRequest
from kintsugi.taskgraph.constraints import Constraint
from kintsugi.taskgraph.features import ArmState, Features, ObjectState

_CONSTRAINT: TypeAdapter = TypeAdapter(Constraint)
TOL_M = 0.005
TOL_DEG = 3.0
"""What a look at the scene cannot tell apart from satisfied: a few millimetres, a few degrees."""
ANGULAR = frozenset({"upright", "tilted"})


class _Seen:
    """One seen object as the checks read it: every feature the request gives (`extent` too: `within` reads a
    container's footprint from it; without it a capsule in the tray was "unseen", and the re-planners
    re-planned the put-inside until their action budget ran out on every coffee-tray trial)."""

    __slots__ = ("centroid", "axis", "n_points", "extremes", "extent")

    def __init__(self, o: Any) -> None:
        self.centroid, self.axis, self.n_points, self.extremes = o.centroid, o.axis, o.n_points, o.extremes
        self.extent = getattr(o, "extent", None)
        if self.axis is None and looks_upright(o):
            # No axis (a cube): upright by the composer's own rule, so a planned "upright" reads as met, as a
            # look at a cube held face down would; not "unseen", which failed DoReMi's every check on the block.
            self.axis = (0.0, 0.0, 1.0)


def features_of(request: VerifyRequest) -> Features:
    objects = {o.name: _Seen(o) for o in request.objects if o.visible and o.centroid is not None}
    arms = {a.name: ArmState(eef=a.tcp_pos, opening=a.gripper_opening_m, closed=a.gripper_closed,
                             touching=frozenset(a.holding)) for a in request.arms}
    return Features(objects=objects, arms=arms)


def embedded_verify(request: VerifyRequest) -> VerifyReply:
    f = features_of(request)
    bad = []
    for data in request.constraints:
        try:
            c = _CONSTRAINT.validate_python(data)
        except ValidationError as exc:
            raise BadReply(f"constraint {str(data)[:80]} is not a template: {exc.errors()[0]['msg']}") from None
        v = c.evaluate(f)
        if not v <= (TOL_DEG if c.kind in ANGULAR else TOL_M):
            bad.append(f"{c.kind} {'unseen' if v != v else f'{v:.3g}'}")
    if bad:
        return VerifyReply(success=False, explanation=f"{request.subgoal}: not met ({', '.join(bad)})")
    return VerifyReply(success=True, explanation=f"{request.subgoal}: met")


VERIFY = ROLES.register(Role(name="verify", request=VerifyRequest, reply=VerifyReply,
                             package="kintsugi.methods.agentchord", embedded=embedded_verify, system="system_taskgraph"))


def ask_verify(reasoner: Any, request: VerifyRequest) -> VerifyReply:
    """The verify role on any backend (recorded when the reasoner records)."""
    return ask(reasoner, "verify", request)


__all__ = ["ObjectState", "VERIFY", "ask_verify", "embedded_verify", "features_of"]
