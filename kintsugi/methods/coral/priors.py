"""Physics priors: an object's mass and friction guessed from what it looks like, and the checks on any guess.

`embedded_priors` is the offline backend: a material table keyed by words of the label (what a
VLM knows from appearance: a cutting board is wood, a box is cardboard) times the volume of the
object's known model. It never sees a trial's truth; its guesses are deliberately coarse, and
system identification corrects them.

`check_priors` is the last line between any backend's reply and the planning world: non-finite
numbers and missing objects are rejected (a backend may repair), implausible but finite values are
clamped into physical bounds with a note saying so.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from kintsugi.methods.coral.types import ObjectPrior, PriorsReply, PriorsRequest
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask


@dataclass(frozen=True)
class Material:
    name: str
    density_kg_m3: float
    """Effective density of the whole object (a cardboard box is mostly air)."""
    friction: float
    """Sliding friction against a table top."""
    words: tuple[str, ...]


MATERIALS: tuple[Material, ...] = (
    Material("wood", 650.0, 0.45, ("wood", "wooden", "cutting board", "chopping board", "board", "plank", "block")),
    Material("cardboard", 180.0, 0.5, ("box", "cardboard", "carton", "package", "parcel")),
    Material("plastic", 350.0, 0.35, ("plastic", "container", "bottle", "tub", "crate", "toy")),
    Material("metal", 2000.0, 0.3, ("metal", "steel", "aluminium", "aluminum", "can", "tin", "pan")),
    Material("ceramic", 900.0, 0.5, ("ceramic", "mug", "cup", "plate", "bowl")),
    Material("paper", 700.0, 0.45, ("book", "paper", "notebook")),
    Material("rubber", 1100.0, 0.9, ("rubber", "eraser", "tire", "grip")),
    Material("foam", 40.0, 0.7, ("foam", "sponge")),
)
UNKNOWN = Material("unknown", 500.0, 0.5, ())

MASS_BOUNDS_KG = (0.005, 50.0)
DENSITY_BOUNDS_KG_M3 = (10.0, 20_000.0)
"""Whatever an object looks like, its mass lies within these densities times its model's volume."""
FRICTION_BOUNDS = (0.02, 2.0)


def material_of(label: str) -> Material:
    """The table entry whose words appear in the label; the longest matching word wins ('cutting board' over
    'board'), and labels naming nothing known get the middle-of-the-road entry."""
    text = " " + re.sub(r"[^a-z]+", " ", label.lower()) + " "
    best, best_len = UNKNOWN, 0
    for m in MATERIALS:
        for w in m.words:
            if f" {w} " in text and len(w) > best_len:
                best, best_len = m, len(w)
    return best


def embedded_priors(request: PriorsRequest) -> PriorsReply:
    objects = {}
    for obj in request.objects:
        m = material_of(obj.label)
        volume = obj.volume_m3
        objects[obj.label] = ObjectPrior(mass_kg=round(m.density_kg_m3 * volume, 4), friction=m.friction,
                                         material=m.name)
    why = "; ".join(f"{o.label}: looks {objects[o.label].material}" for o in request.objects)
    return PriorsReply(objects=objects, reasoning=f"density and friction from the material table ({why})")


def parse_priors(raw: Any) -> PriorsReply:
    """A reply as JSON text or a dict -> PriorsReply, or BadReply naming what is wrong."""
    if isinstance(raw, str):
        from kintsugi.reasoning.jsontext import extract_json_object

        raw = extract_json_object(raw)
    if not isinstance(raw, dict):
        raise BadReply(f"priors reply must be a JSON object, not {type(raw).__name__}")
    try:
        return PriorsReply.model_validate(raw)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"]) or "reply"
        raise BadReply(f"priors reply invalid at {where}: {first['msg']}"[:300]) from None


def check_priors(reply: PriorsReply, request: PriorsRequest) -> tuple[PriorsReply, list[str]]:
    """Bounded priors for exactly the requested objects, and a note per clamp or dropped entry."""
    notes: list[str] = []
    wanted = {o.label: o for o in request.objects}
    missing = [label for label in wanted if label not in reply.objects]
    if missing:
        raise BadReply(f"priors reply lacks: {', '.join(missing)}; give mass_kg and friction for every object")
    extra = sorted(set(reply.objects) - set(wanted))
    if extra:
        notes.append(f"ignored priors for objects not in the scene: {', '.join(extra)[:200]}")
    out = {}
    for label, obj in wanted.items():
        prior = reply.objects[label]
        for field in ("mass_kg", "friction"):
            if not math.isfinite(getattr(prior, field)):
                raise BadReply(f"{label}.{field} is {getattr(prior, field)}; give a finite number")
        volume = obj.volume_m3
        lo = max(MASS_BOUNDS_KG[0], DENSITY_BOUNDS_KG_M3[0] * volume)
        hi = max(lo, min(MASS_BOUNDS_KG[1], DENSITY_BOUNDS_KG_M3[1] * volume))
        mass = _clamp(prior.mass_kg, lo, hi, f"{label}.mass_kg", notes)
        friction = _clamp(prior.friction, *FRICTION_BOUNDS, f"{label}.friction", notes)
        out[label] = ObjectPrior(mass_kg=mass, friction=friction, material=prior.material)
    return PriorsReply(objects=out, reasoning=reply.reasoning), notes


PRIORS = ROLES.register(Role(name="priors", request=PriorsRequest, reply=PriorsReply, package="kintsugi.methods.coral",
                          embedded=embedded_priors, system="system_contact",
                          image_labels={"image_png":
                              "the scene camera at the start: the table, the objects, the fixtures "
                              "and the robot's hand"}))


def ask_priors(reasoner: Any, request: PriorsRequest) -> tuple[PriorsReply, list[str]]:
    """The priors role on any backend (embedded table or a model endpoint), checked and clamped; the notes
    say what was clamped or dropped. Recorded in the transcript when the reasoner records."""
    notes: list[str] = []

    def check(reply: PriorsReply) -> PriorsReply:
        checked, found = check_priors(reply, request)
        notes[:] = found
        return checked

    reply = ask(reasoner, "priors", request, check)
    return reply, notes


def _clamp(value: float, lo: float, hi: float, what: str, notes: list[str]) -> float:
    if lo <= value <= hi:
        return value
    clamped = min(max(value, lo), hi)
    notes.append(f"{what} {value:.4g} clamped to {clamped:.4g} (plausible: {lo:.4g}..{hi:.4g} for its size)")
    return clamped


__all__ = ["PRIORS", "MATERIALS", "Material", "ask_priors", "check_priors", "embedded_priors", "material_of", "parse_priors"]
