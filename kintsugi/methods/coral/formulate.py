"""Task formulation role: instruction + scene -> staged cost code (cost language) and contact regions.

The reply is untrusted at every level: JSON that does not parse or fit `FormulationReply` is a
BadReply; the code is checked by the cost language and probe-run in a limited child process
(kintsugi.sandbox) on sample inputs of the control loop's real shapes; every stage must name
functions the code defines, and regions must lie on (or near) their object with a unit-able
normal. Usable-but-odd numbers (a 30 cm contact radius, a 900 s timeout) are clamped with a
note. Only a reply that passes all of it reaches MPPI.

The variables a cost may read are listed in the request (`variables`), so a model sees the
same vocabulary the control loop provides (`kintsugi.methods.coral.env` implements it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import ValidationError

from kintsugi.core.errors import SandboxError
from kintsugi.methods.coral.types import FormulationReply, FormulationRequest, RegionSpec, StageSpec, seed_functions
from kintsugi.reasoning.jsontext import BadReply
from kintsugi.reasoning.roles import ROLES, Role, ask
from kintsugi.sandbox import FUNCTIONS, CostProgram, ProbeLimits, probe

ROLLOUT_VARS: dict[str, str] = {
    "tcp": "(..., 3) tool centre point (bottom of the fingertips), m",
    "tcp_vel": "(..., 3) its velocity, m/s",
    "yaw": "(...) hand yaw, rad",
    "opening": "(...) finger opening, m",
    "force": "(..., 3) force the hand exerts on its surroundings, world frame, N (its own weight tared away)",
    "touch": "(..., 2) left and right finger pad forces, N",
    "ctrl": "(..., 5) commanded x, y, z, yaw, opening",
    "step_change": "(...) squared change of the commanded x, y, z from the previous step (jitter), m^2",
}
OBJECT_VARS: dict[str, str] = {
    "pos": "(..., 3) position of its frame's origin (the centre of its main box), m",
    "vel": "(..., 3) linear velocity, m/s",
    "up": "(..., 3) its z axis in the world (up_z = cos of its tilt)",
    "yaw": "(...) heading of its x axis, rad",
    "lo": "(..., 3) lowest x, y, z of its corners (world bounding box)",
    "hi": "(..., 3) highest x, y, z of its corners",
}
KEPT_DOC = "the value the stage's `keep` function returned at stage entry (e.g. a yaw chosen once)"
STATE_ONLY: dict[str, str] = {
    "elapsed": "seconds since the stage began",
}
CONTACT_DOC = "(...) distance from the TCP to the nearest candidate point of the stage's contact region, m"
MAX_TIMEOUT_S = 30.0
MAX_RADIUS_M = 0.05
MIN_RADIUS_M = 0.002
MAX_REGION_OFFSET_M = 0.03
"""A region centre may lie at most this far outside its object's box."""


def variable_docs(req: FormulationRequest | None, objects: list[str], fixtures: list[str], markers: list[str],
                  contact: bool) -> dict[str, str]:
    """Every variable name cost code may take, with its meaning. (...) = (K, T) over the sampled rollouts in a
    stage's cost; no leading axes in `done` and grip functions, which read the measured state."""
    out = dict(ROLLOUT_VARS)
    for o in objects:
        for key, doc in OBJECT_VARS.items():
            out[f"{o}_{key}"] = f"object {o}: {doc}"
        out[f"{o}_spin"] = f"object {o}: |angular velocity|, rad/s (measured state only)"
        out[f"{o}_half"] = f"object {o}: (3,) half extents of its known model, m"
        for key in ("pos", "yaw", "lo", "hi"):
            out[f"start_{o}_{key}"] = f"object {o}: its {key} when the stage began (constant)"
        out[f"first_{o}_pos"] = f"object {o}: (3,) its position when the attempt began, as in the request (constant)"
    out["start_tcp"] = "(3,) the TCP when the stage began"
    out["start_yaw"] = "the hand yaw when the stage began"
    for f in fixtures:
        out[f"{f}_lo"] = f"fixture {f}: (3,) lowest corner of its box, world"
        out[f"{f}_hi"] = f"fixture {f}: (3,) highest corner"
    for m in markers:
        out[f"{m}_xy"] = f"marker {m}: (2,) centre of the disc on the table"
        out[f"{m}_radius"] = f"marker {m}: radius, m"
    out["max_opening"] = "the gripper's widest opening, m"
    out["finger_length"] = "finger length, m"
    out["table_edge_x"] = "x of the table's front edge, m"
    out.update(STATE_ONLY)
    out["kept"] = KEPT_DOC
    if contact:
        out["contact"] = CONTACT_DOC
    return out


def request_variables(req: FormulationRequest) -> set[str]:
    return set(variable_docs(req, [o.name for o in req.objects], [f.name for f in req.fixtures],
                             [m.name for m in req.markers], req.contact_strategy))


def _quat_yaw(yaw: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=-1)


def sample_env(req: FormulationRequest, lead: tuple[int, ...], seed: int = 0) -> dict[str, np.ndarray]:
    """Plausible values of every variable with leading axes `lead` ((K, T) for costs, () for the measured state):
    the TCP and objects scattered a few cm around the scene's start. Shapes are the loop's, values are not."""
    rng = np.random.default_rng(seed)

    def around(v: Any, spread: float, shape: tuple[int, ...] = (3,)) -> np.ndarray:
        return np.asarray(v, float) + rng.normal(0, spread, (*lead, *shape))

    env: dict[str, np.ndarray] = {
        "tcp": around(req.robot.home_m, 0.05), "tcp_vel": around((0, 0, 0), 0.05), "yaw": around(0.0, 0.3, ()),
        "opening": np.abs(around(0.05, 0.02, ())), "force": around((0, 0, 0), 3.0),
        "touch": np.abs(around((0, 0), 2.0, (2,))), "ctrl": around((0, 0, 0.1, 0, 0.05), 0.05, (5,)),
        "step_change": np.abs(around(0.0, 1e-5, ())),
        "start_tcp": np.asarray(req.robot.home_m, float), "start_yaw": np.asarray(0.0),
        "max_opening": np.asarray(req.robot.max_opening_m), "finger_length": np.asarray(req.robot.finger_length_m),
        "table_edge_x": np.asarray(req.robot.table_edge_x_m), "elapsed": np.asarray(0.5), "kept": np.asarray(0.1),
    }
    for o in req.objects:
        half = np.asarray(o.size_m, float) / 2
        yaw = math.radians(o.yaw_deg)
        env[f"{o.name}_pos"] = around(o.pos_m, 0.01)
        env[f"{o.name}_vel"] = around((0, 0, 0), 0.02)
        up = around((0, 0, 1), 0.2)
        env[f"{o.name}_up"] = up / np.linalg.norm(up, axis=-1, keepdims=True)
        env[f"{o.name}_yaw"] = around(yaw, 0.1, ())
        env[f"{o.name}_lo"] = env[f"{o.name}_pos"] - half
        env[f"{o.name}_hi"] = env[f"{o.name}_pos"] + half
        env[f"{o.name}_spin"] = np.abs(around(0.0, 0.3, ()))
        env[f"{o.name}_half"] = half
        env[f"start_{o.name}_pos"] = np.asarray(o.pos_m, float)
        env[f"first_{o.name}_pos"] = np.asarray(o.pos_m, float)
        env[f"start_{o.name}_yaw"] = np.asarray(yaw)
        env[f"start_{o.name}_lo"] = np.asarray(o.pos_m, float) - half
        env[f"start_{o.name}_hi"] = np.asarray(o.pos_m, float) + half
    for f in req.fixtures:
        env[f"{f.name}_lo"], env[f"{f.name}_hi"] = np.asarray(f.lo_m, float), np.asarray(f.hi_m, float)
    for m in req.markers:
        env[f"{m.name}_xy"], env[f"{m.name}_radius"] = np.asarray([m.x_m, m.y_m]), np.asarray(m.radius_m)
    if req.contact_strategy:
        env["contact"] = np.abs(around(0.03, 0.02, ()))
    return env


def parse_formulation(raw: Any) -> FormulationReply:
    """A reply as JSON text or a dict -> FormulationReply, or BadReply naming what is wrong."""
    if isinstance(raw, str):
        from kintsugi.reasoning.jsontext import extract_json_object

        raw = extract_json_object(raw)
    if not isinstance(raw, dict):
        raise BadReply(f"formulation reply must be a JSON object, not {type(raw).__name__}")
    try:
        return FormulationReply.model_validate(raw)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"]) or "reply"
        raise BadReply(f"formulation reply invalid at {where}: {first['msg']}"[:300]) from None


def check_regions(regions: list[RegionSpec], req: FormulationRequest, notes: list[str]) -> list[RegionSpec]:
    """Regions on known objects, finite, near their object, with a usable normal; radius and offsets clamped."""
    sizes = {o.name: o.size_m for o in req.objects}
    labels = {o.label: o.name for o in req.objects}
    out = []
    for i, r in enumerate(regions):
        name = r.object if r.object in sizes else labels.get(r.object)
        if name is None:
            raise BadReply(f"regions[{i}].object {r.object[:40]!r} is not in the scene; objects: {', '.join(sizes)}")
        nums = [*r.center, *r.normal, r.radius, r.standoff, r.drop]
        if not all(math.isfinite(x) for x in nums):
            raise BadReply(f"regions[{i}] holds a number that is not finite; give metres")
        n = math.hypot(*r.normal)  # no overflow: a 1e154 component squared is inf, and x / inf = 0
        if n < 1e-6:
            raise BadReply(f"regions[{i}].normal is zero; give the outward surface normal, e.g. [-1, 0, 0]")
        half = [s / 2 for s in sizes[name]]
        outside = max(abs(c) - h for c, h in zip(r.center, half))
        if outside > MAX_REGION_OFFSET_M:
            raise BadReply(f"regions[{i}].center is {outside * 100:.1f} cm outside {name}'s box (half extents "
                           f"{', '.join(f'{h:.3f}' for h in half)} m); give a point on its surface, object frame")
        radius = _clamp(r.radius, MIN_RADIUS_M, MAX_RADIUS_M, f"regions[{i}].radius", notes)
        standoff = _clamp(r.standoff, 0.0, 0.05, f"regions[{i}].standoff", notes)
        drop = _clamp(r.drop, 0.0, 0.05, f"regions[{i}].drop", notes)
        out.append(r.model_copy(update={"object": name, "normal": tuple(x / n for x in r.normal), "radius": radius,
                                        "standoff": standoff, "drop": drop}))
    return out


def check_stages(stages: list[StageSpec], program: CostProgram, regions: list[RegionSpec], req: FormulationRequest,
                 notes: list[str]) -> list[StageSpec]:
    out = []
    for i, s in enumerate(stages):
        for what in ("cost", "done"):
            fn = getattr(s, what)
            if not program.has(fn):
                raise BadReply(f"stages[{i}].{what} names {fn[:40]!r}, which the code does not define; it defines: "
                               f"{', '.join(program.signatures)[:300]}")
        grip = s.grip
        if isinstance(grip, str) and grip not in ("open", "closed", "free") and not program.has(grip):
            raise BadReply(f"stages[{i}].grip {grip[:40]!r} is neither open/closed/free, a number, nor a function "
                           "of the code")
        if isinstance(grip, float):
            if not math.isfinite(grip):
                raise BadReply(f"stages[{i}].grip is not finite")
            grip = _clamp(grip, 0.0, req.robot.max_opening_m, f"stages[{i}].grip", notes)
        if s.keep is not None and not program.has(s.keep):
            raise BadReply(f"stages[{i}].keep names {s.keep[:40]!r}, which the code does not define")
        if s.region is not None and not 0 <= s.region < len(regions):
            raise BadReply(f"stages[{i}].region {s.region} is not an index into regions (0..{len(regions) - 1})")
        if "contact" in program.signatures[s.cost].params and s.region is None:
            raise BadReply(f"stages[{i}] ({s.name}) reads `contact` but names no region")
        for key in ("timeout_s", "hold_s", "noise_scale"):
            if not math.isfinite(getattr(s, key)):
                raise BadReply(f"stages[{i}].{key} is not finite")
        press = s.press_n
        if press is not None:
            if not math.isfinite(press):
                raise BadReply(f"stages[{i}].press_n is not finite")
            press = math.copysign(_clamp(abs(press), 0.0, req.robot.force_limit_n, f"stages[{i}].press_n", notes),
                                  press)
        out.append(s.model_copy(update={
            "grip": grip, "press_n": press,
            "timeout_s": _clamp(s.timeout_s, 0.2, MAX_TIMEOUT_S, f"stages[{i}].timeout_s", notes),
            "hold_s": _clamp(s.hold_s, 0.0, MAX_TIMEOUT_S / 2, f"stages[{i}].hold_s", notes),
            "noise_scale": _clamp(s.noise_scale, 0.02, 3.0, f"stages[{i}].noise_scale", notes)}))
    return out


_PROBED: dict[tuple, tuple[str | None, dict[str, float]]] = {}
"""(source, variables, shapes, limits) -> the probe's refusal (or None) and its seconds per call: the probe is deterministic for the same code
and sample inputs (seeded), so a repeated source (a memory recall, a fuzz campaign) is probed once per process."""


def compile_code(source: str, req: FormulationRequest) -> CostProgram:
    try:
        return CostProgram.compile(source, request_variables(req))
    except SandboxError as exc:
        raise BadReply(f"cost code refused ({exc.kind}): {exc}"[:600]) from None


def probe_code(program: CostProgram, stages: list[StageSpec], req: FormulationRequest, samples: int, steps: int,
               limits: ProbeLimits = ProbeLimits()) -> None:
    """Probe every stage function in the limited child: costs on (K, T) rollouts; done, grip, keep and seed
    functions on one measured state. Any failure is a BadReply quoting the sandbox's message."""
    variables = request_variables(req)
    costs = sorted({s.cost for s in stages})
    states = sorted({s.done for s in stages} | {s.grip for s in stages if isinstance(s.grip, str) and program.has(s.grip)}
                    | {s.keep for s in stages if s.keep}
                    | {name for s in stages for name in seed_functions(s.cost, program.has)})
    key = (program.source, frozenset(variables), tuple(costs), tuple(states), samples, steps, limits)
    if key not in _PROBED:
        try:
            timed = probe(program.source, variables, {c: (samples, steps) for c in costs},
                          sample_env(req, (samples, steps)), limits).seconds_per_call
            timed |= probe(program.source, variables, {c: () for c in states}, sample_env(req, ()),
                           limits).seconds_per_call
            _PROBED[key] = (None, timed)
        except SandboxError as exc:
            _PROBED[key] = (f"cost code refused ({exc.kind}): {exc}"[:600], {})
        if len(_PROBED) > 256:
            _PROBED.pop(next(iter(_PROBED)))
    refusal, timed = _PROBED[key]
    if refusal is not None:
        raise BadReply(refusal)
    program.probed_s.update(timed)  # the loop bounds every call against what the probe measured


def check_formulation(reply: FormulationReply, req: FormulationRequest, samples: int, steps: int,
                      limits: ProbeLimits = ProbeLimits()) -> tuple[FormulationReply, CostProgram, list[str]]:
    """Everything a reply must pass before MPPI: regions, code (compiled, probed), stages; notes say what was clamped."""
    notes: list[str] = []
    if not req.contact_strategy and reply.regions:
        notes.append("regions dropped: this method runs without a contact strategy")
        reply = reply.model_copy(update={"regions": [], "stages": [s.model_copy(update={"region": None})
                                                                    for s in reply.stages]})
    regions = check_regions(reply.regions, req, notes)
    program = compile_code(reply.source, req)
    stages = check_stages(reply.stages, program, regions, req, notes)
    probe_code(program, stages, req, samples, steps, limits)
    knobs = {k: v for k, v in reply.knobs.items() if math.isfinite(v)}
    return reply.model_copy(update={"regions": regions, "stages": stages, "knobs": knobs}), program, notes


def embedded_formulation(req: FormulationRequest) -> FormulationReply:
    from kintsugi.core.errors import ReasoningError
    from kintsugi.methods.coral.costlib import NotUnderstood, compose

    try:
        return compose(req)
    except NotUnderstood as exc:
        raise ReasoningError(f"embedded formulation: {exc}") from None


FORMULATE = ROLES.register(Role(name="formulate", request=FormulationRequest, reply=FormulationReply,
                                package="kintsugi.methods.coral", embedded=embedded_formulation,
                                system="system_contact",
                                image_labels={"image_png":
                                    "the scene camera at the start: the table, the objects, the fixtures "
                                    "and the robot's hand"}))


def ask_formulation(reasoner: Any, req: FormulationRequest, samples: int, steps: int,
                    limits: ProbeLimits = ProbeLimits()) -> tuple[FormulationReply, CostProgram, list[str]]:
    """The formulation role on any backend, checked end to end (the openai backend gets one repair round)."""
    found: dict[str, Any] = {}

    def check(reply: FormulationReply) -> FormulationReply:
        checked, program, notes = check_formulation(reply, req, samples, steps, limits)
        found.update(program=program, notes=notes)
        return checked

    reply = ask(reasoner, "formulate", req, check)
    return reply, found["program"], found["notes"]


def _clamp(value: float, lo: float, hi: float, what: str, notes: list[str]) -> float:
    if lo <= value <= hi:
        return value
    clamped = min(max(value, lo), hi)
    notes.append(f"{what} {value:.4g} clamped to {clamped:.4g} (allowed {lo:g}..{hi:g})")
    return clamped


__all__ = ["FORMULATE", "ask_formulation", "check_formulation", "embedded_formulation", "parse_formulation", "request_variables",
           "sample_env", "variable_docs"]
