"""One realistic request per registered role of every system, built without a simulator, for driving a
reasoner backend or a real model server through every role. `REQUESTS` maps a role name to a builder;
`system_roles()` lists the roles the built-in methods register (the conformance suite fails when one has no
builder)."""

from __future__ import annotations

from typing import Any, Callable

from pydantic import BaseModel


def _judge() -> BaseModel:
    from kintsugi.testing.peg_requests import judge_request

    return judge_request()


def _analyze() -> BaseModel:
    from kintsugi.testing.peg_requests import analyze_request

    return analyze_request()


def _plan() -> BaseModel:
    from kintsugi.testing.peg_requests import plan_request

    return plan_request()


def _composer() -> BaseModel:
    from kintsugi.testing.pour_requests import composer_request

    return composer_request()


def _arranger() -> BaseModel:
    from kintsugi.methods.agentchord.composer import COMPOSER
    from kintsugi.testing.pour_requests import arranger_request, composer_request

    request = composer_request()
    return arranger_request(COMPOSER.embedded(request), request)


def _verify() -> BaseModel:
    from kintsugi.methods.agentchord.types import SeenArm, SeenObject, VerifyRequest

    tray = SeenObject(name="tray", visible=True, centroid=(0.37, 0.0, 0.012), top_z=0.027, bottom_z=0.0,
                      tilt_deg=90.0, upright=False, extent=(0.30, 0.20, 0.027), extremes={}, axis=(1.0, 0.0, 0.0),
                      n_points=900)
    capsule = SeenObject(name="capsule", visible=True, centroid=(0.40, 0.05, 0.03), top_z=0.045, bottom_z=0.015,
                         tilt_deg=0.0, upright=True, extent=(0.03, 0.034, 0.03), extremes={}, axis=(0.0, 0.0, 1.0),
                         n_points=150)
    arm = SeenArm(name="left", tcp_pos=(0.2, 0.3, 0.3), gripper_opening_m=0.1, gripper_closed=False, holding=[])
    within = {"kind": "within", "point": {"entity": "capsule"}, "container": "tray", "margin": 0.01}
    return VerifyRequest(task="put the capsule in the tray", subgoal="inside(capsule, tray)", constraints=[within],
                         objects=[tray, capsule], arms=[arm])


def _priors() -> BaseModel:
    from kintsugi.methods.coral.types import ObjectView, PriorsRequest

    return PriorsRequest(task="Push the box against the wall and keep pressing it with a constant force of 5 N.",
                         objects=[ObjectView(label="box", size_m=(0.06, 0.07, 0.05))])


def _formulate() -> BaseModel:
    from kintsugi.testing.push_requests import PUSH

    return PUSH


def _adapt() -> BaseModel:
    from kintsugi.methods.coral.formulate import embedded_formulation
    from kintsugi.methods.coral.types import AdaptRequest, AttemptHistory
    from kintsugi.testing.push_requests import PUSH

    plan = embedded_formulation(PUSH)
    history = AttemptHistory(attempt=1, stages=[], failed_stage=plan.stages[-1].name if plan.stages else None,
                             max_force_n=3.0, mean_press_force_n=3.2, object_travel_m={"box": 0.1},
                             object_tilt_deg={"box": 1.0})
    return AdaptRequest(task=PUSH.task, scene=PUSH, beliefs=PUSH.priors, source=plan.source, stages=plan.stages,
                        regions=plan.regions, knobs=plan.knobs, history=[history])


REQUESTS: dict[str, Callable[[], BaseModel]] = {
    "judge": _judge, "analyze": _analyze, "plan": _plan,
    "composer": _composer, "arranger": _arranger, "verify": _verify,
    "priors": _priors, "formulate": _formulate, "adapt": _adapt,
}
"""Role name -> a request of that role (system A: judge, analyze, plan; B: composer, arranger, verify;
C: priors, formulate, adapt)."""


def system_roles() -> list[str]:
    """Every role registered by the built-in methods (importing their packages)."""
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import METHODS
    from kintsugi.reasoning.preflight import roles_of

    load_builtins()
    own = [e for e in METHODS if e.factory.__module__.startswith("kintsugi.")]  # built-in methods, not plugins
    return sorted({r.name for entry in own for r in roles_of(entry)})


def build(role: str) -> Any:
    """A request of `role` (KeyError for a role without a builder)."""
    return REQUESTS[role]()
