"""CoRAL's beliefs between the roles: the priors' stress test, and what a remembered episode carries over."""

from __future__ import annotations

import json
import math
from typing import Any


def stressed(beliefs: dict[str, Any], coral: Any) -> tuple[dict[str, Any], str | None]:
    """The priors as `coral.prior_mass_scale` / `prior_friction_scale` distort them (a stress test of the outer
    loop: a model that misjudged the material), and the event line saying so; unchanged at scale 1."""
    m, f = coral.prior_mass_scale, coral.prior_friction_scale
    if (m, f) == (1.0, 1.0):
        return beliefs, None
    return ({k: v.model_copy(update={"mass_kg": v.mass_kg * m, "friction": v.friction * f}) for k, v in beliefs.items()},
            f"stress: the priors scaled x{m:g} in mass and x{f:g} in friction")


def transfer(stored: Any, prior_now: Any, prior_then: dict | None) -> Any:
    """A remembered belief for this trial's object. Friction is the material's and carries over as it was
    refined; mass carries over as the refinement's correction of that episode's prior (the same material, another
    size: the prior scales with the box's volume, a remembered absolute mass would not). An episode stored without
    its priors gives its beliefs as they are."""
    from kintsugi.methods.coral.types import ObjectPrior

    out = ObjectPrior.model_validate(stored.model_dump())
    try:
        then = float(prior_then["mass_kg"]) if prior_then else 0.0
    except (KeyError, TypeError, ValueError):
        then = 0.0
    if then > 0 and math.isfinite(then):
        out = out.model_copy(update={"mass_kg": prior_now.mass_kg * out.mass_kg / then})
    return out


def episode_notes(episode: Any) -> dict[str, Any]:
    try:
        out = json.loads(episode.notes or "{}")
    except ValueError:
        return {}
    return out if isinstance(out, dict) else {}


def rescale(episode: Any, req: Any) -> list[Any]:
    """Stored regions in the object's frame, scaled per axis from the stored model's size to this one's."""
    then = {o.label: o.size_m for o in episode.objects}
    now = {o.name: o.size_m for o in req.objects}
    out = []
    for r in episode.regions:
        if r.object in then and r.object in now:
            k = [a / b for a, b in zip(now[r.object], then[r.object])]
            r = r.model_copy(update={"center": tuple(c * s for c, s in zip(r.center, k))})
        out.append(r)
    return out


def dump(beliefs: dict) -> dict[str, dict[str, float]]:
    return {k: {"mass_kg": round(v.mass_kg, 5), "friction": round(v.friction, 5)} for k, v in beliefs.items()}

