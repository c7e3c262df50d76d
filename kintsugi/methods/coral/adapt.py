"""Adaptation role (CoRAL's outer loop): a failed attempt's history -> corrected physics and/or rewritten cost.

The request holds what the robot logged (per-stage outcome and planning cost, forces, how far
and how much each object moved and turned) and the system identification's fit on that log.
Two corrections, as in the paper: world-model correction (new masses and frictions) and
strategy refinement (a rewritten cost: new weights, thresholds, timeouts, contact height).

The embedded backend is rule-based: it adopts the sysid fit when the fit explains the log
better than the current beliefs, and refines the strategy by rules on the failure's signature
(the stage that failed, whether its planning cost fell, the pressing force, a dropped object),
then writes the code again with the cost library. Any backend's reply is checked like a
formulation: beliefs clamped to physical bounds, new code compiled and probed in the sandbox.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import ValidationError

from kintsugi.methods.coral.types import AdaptReply, AdaptRequest, FormulationReply, ObjectPrior
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask
from kintsugi.methods.coral.priors import DENSITY_BOUNDS_KG_M3, FRICTION_BOUNDS, MASS_BOUNDS_KG
from kintsugi.sandbox import CostProgram, ProbeLimits

KNOB_CAP = 4.0
"""A refined weight stays within this factor of the library default (the paper: keep weights comparable)."""
ESCALATION_CAP = {"timeout_scale": 2.0}
"""Knobs an outer loop escalates on every failure ("more time") stop at this multiple of their default."""


def parse_adaptation(raw: Any) -> AdaptReply:
    if isinstance(raw, str):
        from kintsugi.reasoning.jsontext import extract_json_object

        raw = extract_json_object(raw)
    if not isinstance(raw, dict):
        raise BadReply(f"adaptation reply must be a JSON object, not {type(raw).__name__}")
    try:
        return AdaptReply.model_validate(raw)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"]) or "reply"
        raise BadReply(f"adaptation reply invalid at {where}: {first['msg']}"[:300]) from None


def _scale(knobs: dict[str, float], key: str, factor: float, notes: list[str]) -> None:
    from kintsugi.methods.coral.costlib import DEFAULT_KNOBS

    base = DEFAULT_KNOBS[key]
    old = knobs.get(key, base)
    cap = ESCALATION_CAP.get(key, KNOB_CAP)
    new = min(max(old * factor, base / cap), base * cap)
    if new != old:
        knobs[key] = round(new, 6)
        notes.append(f"{key} {old:g} -> {new:g}")


def _shift(knobs: dict[str, float], key: str, delta: float, lo: float, hi: float, notes: list[str]) -> None:
    from kintsugi.methods.coral.costlib import DEFAULT_KNOBS

    old = knobs.get(key, DEFAULT_KNOBS[key])
    new = min(max(old + delta, lo), hi)
    if new != old:
        knobs[key] = round(new, 6)
        notes.append(f"{key} {old:g} -> {new:g}")


def embedded_adaptation(req: AdaptRequest) -> AdaptReply:
    """Adopt a sysid fit that explains the log; refine the cost by rules on how the last attempt failed."""
    from kintsugi.methods.coral.costlib import NotUnderstood, compose

    why: list[str] = []
    beliefs = None
    s = req.sysid
    if s is not None and not s.adopted:
        why.append(f"World model kept: {s.kept_because or 'the log does not identify the fit'}.")
    elif s is not None and math.isfinite(s.loss_fit) and s.loss_fit < s.loss_prior:
        beliefs = dict(req.beliefs)
        old = req.beliefs.get(s.object)
        beliefs[s.object] = ObjectPrior(mass_kg=s.mass_kg, friction=s.friction,
                                        material=old.material if old else "")
        was = f"{old.mass_kg:.3g} kg, friction {old.friction:.3g}" if old else "no belief"
        why.append(f"World model: the log of {s.windows} windows is explained better by {s.object} at "
                   f"{s.mass_kg:.3g} kg, friction {s.friction:.3g} (was {was}; replay loss {s.loss_prior:.3g} -> "
                   f"{s.loss_fit:.3g}).")
    elif s is not None:
        why.append(f"World model kept: the fit did not explain the log better (loss {s.loss_prior:.3g} -> "
                   f"{s.loss_fit:.3g}).")
    else:
        why.append("World model kept: nothing in the log to fit (the object never moved and nothing was felt).")
    if not req.refine_strategy:
        return AdaptReply(diagnosis=" ".join(why), beliefs=beliefs)
    last = req.history[-1]
    knobs = dict(req.knobs)
    notes: list[str] = []
    failed = last.failed_stage
    outcome = next((x for x in last.stages if x.name == failed), None)
    if last.cost_error:
        why.append(f"The cost code failed in the loop ({last.cost_error[:120]}); written again from the library.")
    elif last.broken:
        why.append(f"The attempt broke what the instruction forbids ({last.broken[:160]}); the cost is kept and the "
                   "attempt runs again.")
    elif failed is None:
        why.append("Every stage finished but the task was not judged done; the cost is kept, timeouts extended.")
        _scale(knobs, "timeout_scale", 1.25, notes)
    else:
        stalled = (outcome is not None and outcome.cost_first is not None and outcome.cost_last is not None
                   and outcome.cost_last > 0.8 * outcome.cost_first)
        why.append(f"Stage '{failed}' did not finish in {outcome.seconds if outcome else 0:.1f} s"
                   + (" and its planning cost hardly fell: its goal terms are too weak against the others." if stalled
                      else "; its cost fell, so it ran out of time: more time."))
        _scale(knobs, "timeout_scale", 1.3, notes)
        if stalled:
            _scale(knobs, "w_reach", 1.5, notes)
            _scale(knobs, "w_contact", 1.5, notes)
        if failed == "press" and last.mean_press_force_n is not None:
            why.append(f"The pressing force averaged {last.mean_press_force_n:.2f} N: weigh the force error more.")
            _scale(knobs, "w_force", 1.5, notes)
        if failed in ("tip", "pivot"):
            why.append("The object did not turn far enough: push higher on its back and weigh its tilt more.")
            _shift(knobs, "push_height", 0.05, 0.5, 0.85, notes)
            _scale(knobs, "w_tip", 1.5, notes)
        if failed == "push":
            _scale(knobs, "w_gap", 1.5, notes)
        names = {st.name for st in req.stages}
        # closed fingers that push (a flip) lose touch with each other, not with a held object: only a plan that
        # grasps can drop what it holds
        if (last.touch_lost_while_held and "grasp" in names) or failed in ("lift", "carry"):
            why.append("The object slipped from the pinch: ask for a firmer grasp before lifting.")
            _shift(knobs, "touch_n", 1.0, 1.0, 8.0, notes)
        if failed in ("withdraw", "clear", "back", "settle") and "pivot" in names:
            why.append("The object did not come to rest turned and down on the table after the hand drew back: "
                       "turn it further over the fixture first.")
            _shift(knobs, "pivot_deg", 10.0, 100.0, 160.0, notes)
        elif failed == "withdraw":
            why.append("The object was not at rest on its side when the hand drew back: tip it further first.")
            _shift(knobs, "tip_deg", 10.0, 30.0, 80.0, notes)
    if notes:
        why.append("Cost rewritten: " + "; ".join(notes) + ".")
    try:
        rewritten = compose(req.scene, knobs)
    except NotUnderstood as exc:
        why.append(f"(no rewrite: {exc})")
        return AdaptReply(diagnosis=" ".join(why), beliefs=beliefs)
    return AdaptReply(diagnosis=" ".join(why), beliefs=beliefs, source=rewritten.source, stages=rewritten.stages,
                      regions=rewritten.regions, knobs=rewritten.knobs)


def check_beliefs(beliefs: dict[str, ObjectPrior], req: AdaptRequest, notes: list[str]) -> dict[str, ObjectPrior]:
    """Beliefs for objects of the scene only, finite, clamped to what their size allows."""
    sizes = {o.name: o.size_m for o in req.scene.objects}
    out = dict(req.beliefs)
    for name, b in beliefs.items():
        if name not in sizes:
            raise BadReply(f"beliefs name {name[:40]!r}, not an object of the scene ({', '.join(sizes)})")
        if not (math.isfinite(b.mass_kg) and math.isfinite(b.friction)):
            raise BadReply(f"beliefs.{name}: mass_kg and friction must be finite numbers")
        volume = math.prod(sizes[name])
        lo = max(MASS_BOUNDS_KG[0], DENSITY_BOUNDS_KG_M3[0] * volume)
        hi = max(lo, min(MASS_BOUNDS_KG[1], DENSITY_BOUNDS_KG_M3[1] * volume))
        mass = min(max(b.mass_kg, lo), hi)
        friction = min(max(b.friction, FRICTION_BOUNDS[0]), FRICTION_BOUNDS[1])
        if mass != b.mass_kg:
            notes.append(f"beliefs.{name}.mass_kg {b.mass_kg:.4g} clamped to {mass:.4g}")
        if friction != b.friction:
            notes.append(f"beliefs.{name}.friction {b.friction:.4g} clamped to {friction:.4g}")
        out[name] = ObjectPrior(mass_kg=mass, friction=friction, material=b.material)
    return out


def check_adaptation(reply: AdaptReply, req: AdaptRequest, samples: int, steps: int,
                     limits: ProbeLimits = ProbeLimits()
                     ) -> tuple[AdaptReply, FormulationReply, CostProgram | None, list[str]]:
    """(checked reply, the plan to run next, its compiled program if the code changed, notes)."""
    from kintsugi.methods.coral.formulate import check_formulation

    notes: list[str] = []
    beliefs = check_beliefs(reply.beliefs, req, notes) if reply.beliefs is not None else None
    current = FormulationReply(source=req.source, stages=req.stages, regions=req.regions, knobs=req.knobs)
    changed = any(x is not None for x in (reply.source, reply.stages, reply.regions))
    program = None
    plan = current
    if changed:
        try:
            plan = FormulationReply(source=reply.source if reply.source is not None else req.source,
                                    stages=reply.stages if reply.stages is not None else req.stages,
                                    regions=reply.regions if reply.regions is not None else req.regions,
                                    knobs=reply.knobs if reply.knobs is not None else req.knobs,
                                    reasoning=reply.diagnosis[:4000])
        except ValidationError as exc:
            first = exc.errors()[0]
            raise BadReply(f"adaptation's rewritten plan invalid at {'.'.join(map(str, first['loc']))}: "
                           f"{first['msg']}"[:300]) from None
        plan, program, found = check_formulation(plan, req.scene, samples, steps, limits)
        notes += found
    return reply.model_copy(update={"beliefs": beliefs}), plan, program, notes


ADAPT = ROLES.register(Role(name="adapt", request=AdaptRequest, reply=AdaptReply, package="kintsugi.methods.coral",
                         embedded=embedded_adaptation, system="system_contact",
                         image_labels={"scene.image_png":
                             "the scene camera at the start: the table, the objects, the fixtures "
                             "and the robot's hand"}))


def ask_adaptation(reasoner: Any, req: AdaptRequest, samples: int, steps: int, limits: ProbeLimits = ProbeLimits()
                   ) -> tuple[AdaptReply, FormulationReply, CostProgram | None, list[str]]:
    found: dict[str, Any] = {}

    def check(reply: AdaptReply) -> AdaptReply:
        checked, plan, program, notes = check_adaptation(reply, req, samples, steps, limits)
        found.update(plan=plan, program=program, notes=notes)
        return checked

    reply = ask(reasoner, "adapt", req, check)
    return reply, found["plan"], found["program"], found["notes"]


__all__ = ["ADAPT", "ask_adaptation", "check_adaptation", "check_beliefs", "embedded_adaptation", "parse_adaptation"]
