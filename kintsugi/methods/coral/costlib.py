"""The embedded formulation backend: cost code composed from a library of cost terms.

No lookup by task name. The instruction's words choose skills (pick / put down on / push
against / press with N / flip over / pivot against / push over the table edge, then pick) and
the objects' geometry fills them in:
which object the words name, whether it stands tall or lies flat, which fixture or marker it
goes to, which face to push on (the face turned away from the fixture), how high to grasp and
which side fits the gripper. Every skill writes its stages as functions of the cost language
(kintsugi.sandbox): the same untrusted-code path a model's reply takes, compiled and probed
before MPPI sees it. The code reads sizes and poses through variables (`box_half`,
`start_box_pos`, ...), never as baked numbers, so a stored episode's code fits a new trial
with a differently sized box. `knobs` are the weights and thresholds the code is written with;
the adaptation role refines them and the library writes the code again. Moves to a known pose also give
their goal as `<cost>_seed_<axis>` functions: the plan restarts there (see kintsugi.methods.coral.stages).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from kintsugi.methods.coral.types import FormulationReply, FormulationRequest, ObjectState, RegionSpec, StageSpec

DEFAULT_KNOBS: dict[str, float] = {
    "w_reach": 10.0, "w_smooth": 50.0, "w_yaw": 1.0, "w_contact": 10.0, "w_gap": 30.0, "w_force": 3.0,
    "w_press_contact": 300.0, "w_tip": 5.0,
    "clear_m": 0.025, "lift_m": 0.12, "carry_z_m": 0.14, "set_down_m": 0.004, "touch_n": 2.0,
    "push_z_m": 0.008, "push_height": 0.7, "paddle_m": 0.01, "push_speed_m_s": 0.08,
    "tip_deg": 45.0, "pivot_deg": 125.0, "reach_over_m": 0.06, "fling_m_s": 0.3, "rest_m": 0.005, "flip_deg": 75.0, "reach_tol_m": 0.012, "force_tol_n": 0.4,
    "timeout_scale": 1.0, "hold_press_s": 2.0,
    "overhang_m": 0.09, "pinch_past_edge_m": 0.035, "under_edge_z_m": -0.012, "travel_z_m": 0.07,
    "edge_lift_z_m": 0.28, "edge_touch_n": 5.0, "still_m_s": 0.03, "kept_m": 0.02,
}
"""Weights (cost units per metre, newton, radian) and thresholds the skills are written with."""

HELPERS = '''def wrap_pi(yaw):
    """Signed distance of an angle to the nearest multiple of pi (a pinch across a box is symmetric)."""
    return (yaw + pi / 2) % pi - pi / 2
'''


@dataclass
class Plan:
    stages: list[StageSpec] = field(default_factory=list)
    regions: list[RegionSpec] = field(default_factory=list)
    code: list[str] = field(default_factory=list)
    why: list[str] = field(default_factory=list)


class NotUnderstood(ValueError):
    """The instruction names no skill the library has, or no object the scene holds."""


def words(text: str) -> list[str]:
    return [w.strip(".") for w in re.findall(r"[a-z0-9.]+", text.lower()) if w.strip(".")]


def target_object(req: FormulationRequest) -> ObjectState:
    """The object the instruction names first (its label or name; plural forms count)."""
    text = " " + " ".join(words(req.task)) + " "
    best: tuple[int, ObjectState] | None = None
    for o in req.objects:
        for w in {o.name.lower(), *words(o.label)}:
            w = re.sub(r"\d+$", "", w)
            for form in (w, w + "s", w + "es"):
                i = text.find(f" {form} ")
                if i >= 0 and (best is None or i < best[0]):
                    best = (i, o)
    if best is None:
        raise NotUnderstood(f"the instruction names none of the objects: {', '.join(o.label for o in req.objects)}")
    return best[1]


def force_n(text: str) -> float | None:
    m = re.search(r"(\d+(?:\.\d+)?)\s*(?:n|newtons?)\b", text.lower())
    return float(m.group(1)) if m else None


def duration_s(text: str) -> float | None:
    """'for 2 seconds', 'for 1.5 s': how long the instruction asks a press to last."""
    m = re.search(r"for\s+(\d+(?:\.\d+)?)\s*(?:s|secs?|seconds?)\b", text.lower())
    return float(m.group(1)) if m else None


def tall(o: ObjectState) -> bool:
    """Stands on a small face: taller than it is wide, and upright."""
    return o.size_m[2] > max(o.size_m[0], o.size_m[1]) and o.upright_deg < 30


def toward(o: ObjectState, req: FormulationRequest) -> tuple[str | None, int, float]:
    """The fixture the object goes to (nearest), the world axis and the sign of the push toward it."""
    if req.fixtures:
        f = min(req.fixtures, key=lambda f: math.dist(_centre(f), o.pos_m))
        c = _centre(f)
        dx, dy = c[0] - o.pos_m[0], c[1] - o.pos_m[1]
    else:  # away from the robot's home: the far side of the object is free
        f, (dx, dy) = None, (o.pos_m[0] - req.robot.home_m[0], o.pos_m[1] - req.robot.home_m[1])
    axis = 0 if abs(dx) >= abs(dy) else 1
    sign = 1.0 if (dx if axis == 0 else dy) >= 0 else -1.0
    return (f.name if f else None), axis, sign


def _centre(f) -> tuple[float, float, float]:  # noqa: ANN001 - a FixtureView
    return tuple((a + b) / 2 for a, b in zip(f.lo_m, f.hi_m))  # type: ignore[return-value]


def back_face(o: ObjectState, axis: int, sign: float, height_frac: float | None, z_m: float, k: dict[str, float]
              ) -> RegionSpec:
    """The face turned away from the push, in the object's frame (its yaw is small): where the closed fingers push.
    `height_frac` of the object's height, or `z_m` above its bottom."""
    half = [s / 2 for s in o.size_m]
    yaw = math.radians(o.yaw_deg)
    # push direction in the object's frame, snapped to its nearest principal axis
    wx, wy = (sign, 0.0) if axis == 0 else (0.0, sign)
    lx, ly = math.cos(yaw) * wx + math.sin(yaw) * wy, -math.sin(yaw) * wx + math.cos(yaw) * wy
    ax, s = (0, math.copysign(1.0, lx)) if abs(lx) >= abs(ly) else (1, math.copysign(1.0, ly))
    z = -half[2] + (height_frac * 2 * half[2] if height_frac is not None else z_m)
    centre = [0.0, 0.0, z]
    normal = [0.0, 0.0, 0.0]
    centre[ax], normal[ax] = -s * half[ax], -s
    return RegionSpec(object=o.name, center=tuple(centre), normal=tuple(normal),  # type: ignore[arg-type]
                      radius=0.01 if height_frac is not None else 0.008, standoff=k["paddle_m"],
                      drop=0.0 if height_frac is not None else 0.006)


def compose(req: FormulationRequest, knobs: dict[str, float] | None = None) -> FormulationReply:
    """Instruction + scene -> staged cost code, stages, contact regions. Raises NotUnderstood."""
    k = {**DEFAULT_KNOBS, **(knobs or {})}
    text = " ".join(words(req.task))
    o = target_object(req)
    plan = Plan(code=[HELPERS])
    contact = req.contact_strategy
    others = [x for x in req.objects if x.name != o.name]
    if ("push" in text or "slide" in text) and "edge" in text and ("pick" in text or "lift" in text):
        _push_over_edge(plan, o, k, contact)
        _pick_past_edge(plan, o, k)
    elif "flip" in text or "tip" in text.split():
        fixture, axis, sign = toward(o, req)
        if not tall(o) and fixture is not None and any(w in text for w in ("curb", "wall", "fixture", "against")):
            _pivot(plan, o, fixture, axis, sign, k, contact)
        else:
            _tip(plan, o, axis, sign, k, contact)
    elif "push" in text or "press" in text:
        fixture, axis, sign = toward(o, req)
        if fixture is None:
            raise NotUnderstood("a push 'against' something needs a fixture in the scene; there is none")
        _push(plan, o, fixture, axis, sign, k, contact)
        f = force_n(req.task)
        if duration_s(req.task) is not None:  # the instruction's duration, else the library's default
            k["hold_press_s"] = duration_s(req.task)
        if f is not None:
            _press(plan, o, fixture, axis, sign, f, k, contact)
    elif "pick" in text or "lift" in text:
        _pick(plan, o, others, k)
        marker = next((m for m in req.markers if any(w in text for w in ("disc", "goal", "marker", "put", "place"))),
                      None)
        if marker is not None and any(w in text for w in (" put ", " place", " on ", "down")):
            _place(plan, o, others, marker.name, k)
        else:
            _settle(plan, "hold", 0.5, "closed", k)
    else:
        raise NotUnderstood("no skill for this instruction: the library knows pick, put down on, push against, "
                            "press with a force, flip over, pivot against a fixture, and push over the table edge "
                            "then pick")
    return FormulationReply(source=_dedup_params("\n\n\n".join(plan.code)), stages=plan.stages, regions=plan.regions,
                            knobs=k, reasoning=" ".join(plan.why))


def _dedup_params(source: str) -> str:
    """A skill may name a variable twice when its terms share one (`box_pos`): keep the first."""
    def fix(m: re.Match) -> str:
        seen: list[str] = []
        for p in (x.strip() for x in m.group(2).split(",")):
            if p and p not in seen:
                seen.append(p)
        return f"def {m.group(1)}({', '.join(seen)}):"
    return re.sub(r"def (\w+)\(([^)]*)\):", fix, source)


# --- skills -----------------------------------------------------------------------------------------------------

def _t(k: dict[str, float], s: float) -> float:
    return round(s * k["timeout_scale"], 3)


def _hold_code(name: str, dx: str = "0.0", dy: str = "0.0", dz: str = "0.0", yaw: str = "start_yaw",
               extra: str = "", w_yaw: str = "W_YAW", seed: bool = False) -> str:
    """A cost holding the TCP at start_tcp + (dx, dy, dz) with a yaw; with `seed`, the plan restarts there."""
    code = f'''def {name}(tcp, yaw, step_change, start_tcp, start_yaw{extra}):
    ex = tcp[..., 0] - start_tcp[0] - {dx}
    ey = tcp[..., 1] - start_tcp[1] - {dy}
    ez = tcp[..., 2] - start_tcp[2] - {dz}
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + {w_yaw} * wrap_pi(yaw - {yaw}) ** 2 + W_SMOOTH * step_change'''
    if seed:
        code += "\n\n\n" + _seed_code(name, "start_tcp, start_yaw", f"start_tcp[0] + {dx}", f"start_tcp[1] + {dy}",
                                        f"start_tcp[2] + {dz}", yaw)
    return code


def _seed_code(cost: str, params: str, x: str, y: str, z: str, yaw: str | None = None) -> str:
    """The stage's goal as the commands its plan restarts from (`<cost>_seed_<axis>`, read at stage entry):
    the servos head straight for it and MPPI refines from there, instead of crawling from the last plan."""
    axes = [("x", x), ("y", y), ("z", z)] + ([("yaw", yaw)] if yaw is not None else [])
    return "\n\n\n".join(f'''def {cost}_seed_{a}({params}):
    return {v}''' for a, v in axes)


def _sub(code: str, k: dict[str, float]) -> str:
    for key in ("w_reach", "w_smooth", "w_yaw", "w_contact", "w_gap", "w_force", "w_press_contact", "w_tip"):
        code = code.replace(key.upper(), repr(round(k[key], 6)))
    return code


def _settle(plan: Plan, name: str, seconds: float, grip: str, k: dict[str, float]) -> None:
    fn = f"{name}_cost"
    plan.code.append(_sub(_hold_code(fn), k))
    plan.code.append(f'''def {name}_done(tcp):
    return 1.0 + 0.0 * tcp[..., 0]''')
    plan.stages.append(StageSpec(name=name, cost=fn, done=f"{name}_done", grip=grip, hold_s=seconds,
                                 timeout_s=seconds + 2.0))


def _pick(plan: Plan, o: ObjectState, others: list[ObjectState], k: dict[str, float]) -> None:
    n = o.name
    d_params = (f", start_{n}_pos" if others else "") + "".join(f", start_{x.name}_pos" for x in others)
    lets, clear_a, clear_b = [], [], []
    for i, x in enumerate(others):
        lets.append(f"    dx{i} = start_{n}_pos[0] - start_{x.name}_pos[0]\n    dy{i} = start_{n}_pos[1] - start_{x.name}_pos[1]"
                    f"\n    q{i} = dx{i} ** 2 + dy{i} ** 2")
        for side, terms in (("a", clear_a), ("b", clear_b)):
            # squared distance from the nearer finger (centre +- f) to the other object: |d|^2 - 2|f.d| + |f|^2
            terms.append(f"q{i} - 2.0 * abs(dx{i} * f{side}x + dy{i} * f{side}y) + r{side} ** 2")
    distances = ("\n" + "\n".join(lets)) if lets else ""

    def nested_min(terms: list[str]) -> str:
        if not terms:
            return "0.0"
        out = terms[0]
        for t in terms[1:]:
            out = f"minimum({out}, {t})"
        return out

    side = f'''    ya = start_{n}_yaw
    yb = start_{n}_yaw + pi / 2
    ra = {n}_half[1] + 0.03
    rb = {n}_half[0] + 0.03
    cax = -sin(ya)
    cay = cos(ya)
    cbx = -sin(yb)
    cby = cos(yb)
    fax = ra * cax
    fay = ra * cay
    fbx = rb * cbx
    fby = rb * cby{distances}
    fit_a = where(2.0 * {n}_half[1] < max_opening - 0.015, 0.0, 1000.0)
    fit_b = where(2.0 * {n}_half[0] < max_opening - 0.015, 0.0, 1000.0)
    score_a = fit_a - 1000.0 * sqrt({nested_min(clear_a)}) + abs(wrap_pi(start_yaw - ya))
    score_b = fit_b - 1000.0 * sqrt({nested_min(clear_b)}) + abs(wrap_pi(start_yaw - yb))
    side = where(score_a <= score_b, 1.0, -1.0)
    aim = start_yaw - wrap_pi(start_yaw - where(side > 0, ya, yb))'''
    # side = +1: pinch across the object's y (hand yaw = its yaw), -1: across its x. A side must fit the open
    # gripper; with other objects around, the side whose open fingers come down farthest from them wins, else
    # the least turn. (Inlined: calls take at most 4 arguments in the cost language.)
    params = f"start_{n}_yaw, start_yaw, {n}_half, max_opening{d_params}"
    plan.code.append(f'''def {n}_open({n}_half, max_opening):
    """Open just wider than the object's wider horizontal side (either side may be the one pinched)."""
    return minimum(max_opening, 2.0 * maximum({n}_half[0], {n}_half[1]) + 0.035)


def {n}_grasp_z({n}_half, finger_length):
    return maximum(0.006, {n}_half[2] - finger_length / 3.0)''')
    plan.code.append(f'''def {n}_aim({params}):
    """The hand yaw to pinch with, chosen once when the stage begins (the variable `kept`)."""
{side}
    return aim''')
    plan.code.append(_sub(f'''def reach_cost(tcp, yaw, step_change, {n}_pos, start_{n}_hi, kept):
    """Above the object with the hand turned across a side that fits."""
    ex = tcp[..., 0] - {n}_pos[..., 0]
    ey = tcp[..., 1] - {n}_pos[..., 1]
    ez = tcp[..., 2] - start_{n}_hi[2] - {k["clear_m"]}
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + W_YAW * wrap_pi(yaw - kept) ** 2 + W_SMOOTH * step_change


def reach_done(tcp, yaw, {n}_pos, start_{n}_hi, kept):
    ex = tcp[..., 0] - {n}_pos[..., 0]
    ey = tcp[..., 1] - {n}_pos[..., 1]
    ez = tcp[..., 2] - start_{n}_hi[2] - {k["clear_m"]}
    return logical_and(sqrt(ex ** 2 + ey ** 2 + ez ** 2) < {k["reach_tol_m"]}, abs(wrap_pi(yaw - kept)) < 0.06)


def descend_cost(tcp, yaw, step_change, {n}_pos, start_{n}_lo, finger_length, {n}_half, start_yaw):
    """Straight down around it, to a pinch height clear of the table, the hand kept turned as it came."""
    ex = tcp[..., 0] - {n}_pos[..., 0]
    ey = tcp[..., 1] - {n}_pos[..., 1]
    ez = tcp[..., 2] - start_{n}_lo[2] - {n}_grasp_z({n}_half, finger_length)
    exy = sqrt(ex ** 2 + ey ** 2)
    return W_REACH * sqrt(exy ** 2 + ez ** 2) + 2.0 * W_REACH * exy + W_YAW * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def descend_cost_seed_x(start_{n}_pos):
    return start_{n}_pos[0]


def descend_cost_seed_y(start_{n}_pos):
    return start_{n}_pos[1]


def descend_cost_seed_z(start_{n}_lo, {n}_half, finger_length):
    return start_{n}_lo[2] + {n}_grasp_z({n}_half, finger_length)


def descend_done(tcp, {n}_pos, start_{n}_lo, {n}_half, finger_length):
    ex = tcp[..., 0] - {n}_pos[..., 0]
    ey = tcp[..., 1] - {n}_pos[..., 1]
    ez = tcp[..., 2] - start_{n}_lo[2] - {n}_grasp_z({n}_half, finger_length)
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.008''', k))
    plan.code.append(_sub(_hold_code("grasp_cost"), k))
    plan.code.append(f'''def grasp_done(touch):
    return min(touch, axis=-1) > {k["touch_n"]}''')
    plan.code.append(_sub(f'''def lift_cost(tcp, yaw, step_change, start_tcp, start_yaw, {n}_pos, start_{n}_pos):
    """Up, with the object: a penalty while the object lags below the lift height."""
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - start_tcp[2] - {k["lift_m"]}
    lag = relu(start_{n}_pos[2] + {k["lift_m"]} - {n}_pos[..., 2])
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + 2.0 * W_REACH * lag + W_YAW * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def lift_done(touch, {n}_pos, start_{n}_pos):
    return logical_and({n}_pos[..., 2] > start_{n}_pos[2] + {k["lift_m"] - 0.02}, min(touch, axis=-1) > 0.5)''', k))
    plan.stages += [
        StageSpec(name="reach", cost="reach_cost", done="reach_done", grip=f"{n}_open", keep=f"{n}_aim",
                  timeout_s=_t(k, 5.0)),
        # restarted at the grasp point with fine sampling noise (as the expert's descent): centimetre jitter here
        # puts a finger on an edge and shoves the object or a neighbour away
        StageSpec(name="descend", cost="descend_cost", done="descend_done", grip=f"{n}_open", noise_scale=0.35,
                  timeout_s=_t(k, 4.0)),
        StageSpec(name="grasp", cost="grasp_cost", done="grasp_done", grip="closed", hold_s=0.2,
                  timeout_s=_t(k, 2.0)),
        StageSpec(name="lift", cost="lift_cost", done="lift_done", grip="closed", timeout_s=_t(k, 4.0)),
    ]
    plan.why.append(f"'{o.label}' is picked: reach above it with the hand turned across a side that fits the "
                    f"gripper{' and clear of ' + ', '.join(x.label for x in others) if others else ''}, descend, "
                    f"close until both pads press {k['touch_n']:g} N, lift {k['lift_m'] * 100:g} cm.")


def _place(plan: Plan, o: ObjectState, others: list[ObjectState], marker: str, k: dict[str, float]) -> None:
    n = o.name
    plan.code.append(_sub(f'''def carry_cost(tcp, yaw, step_change, start_tcp, start_yaw, {n}_pos, start_{n}_pos, {marker}_xy):
    """Above the goal, the object kept where it sits in the hand."""
    ox = start_tcp[0] - start_{n}_pos[0]
    oy = start_tcp[1] - start_{n}_pos[1]
    ex = tcp[..., 0] - {marker}_xy[0] - ox
    ey = tcp[..., 1] - {marker}_xy[1] - oy
    ez = tcp[..., 2] - {k["carry_z_m"]}
    slip = sqrt((tcp[..., 0] - ox - {n}_pos[..., 0]) ** 2 + (tcp[..., 1] - oy - {n}_pos[..., 1]) ** 2)
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + 2.0 * W_REACH * slip + W_YAW * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def carry_done(tcp, tcp_vel, start_tcp, start_{n}_pos, {marker}_xy):
    ex = tcp[..., 0] - {marker}_xy[0] - start_tcp[0] + start_{n}_pos[0]
    ey = tcp[..., 1] - {marker}_xy[1] - start_tcp[1] + start_{n}_pos[1]
    ez = tcp[..., 2] - {k["carry_z_m"]}
    return logical_and(sqrt(ex ** 2 + ey ** 2 + ez ** 2) < {k["reach_tol_m"]}, norm(tcp_vel) < 0.05)


def lower_cost(tcp, yaw, step_change, start_tcp, start_yaw, start_{n}_pos, {n}_half, {marker}_xy):
    """Down until the object's bottom is just above the table, over the goal."""
    ox = start_tcp[0] - start_{n}_pos[0]
    oy = start_tcp[1] - start_{n}_pos[1]
    ex = tcp[..., 0] - {marker}_xy[0] - ox
    ey = tcp[..., 1] - {marker}_xy[1] - oy
    ez = tcp[..., 2] - ({n}_half[2] + {k["set_down_m"]} + start_tcp[2] - start_{n}_pos[2])
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + W_YAW * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def lower_done(tcp, start_tcp, start_{n}_pos, {n}_half, {marker}_xy):
    ex = tcp[..., 0] - {marker}_xy[0] - start_tcp[0] + start_{n}_pos[0]
    ey = tcp[..., 1] - {marker}_xy[1] - start_tcp[1] + start_{n}_pos[1]
    ez = tcp[..., 2] - ({n}_half[2] + {k["set_down_m"]} + start_tcp[2] - start_{n}_pos[2])
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.006''', k))
    plan.code.append(_sub(_hold_code("release_cost"), k))
    plan.code.append('''def release_done(opening, touch, max_opening):
    return logical_and(opening > 0.8 * max_opening, max(touch, axis=-1) < 0.1)''')
    plan.code.append(_sub(_hold_code("withdraw_up_cost", dz="0.08"), k))
    kept = "".join(f", {x.name}_pos, first_{x.name}_pos" for x in others)
    left = "".join(f"\n    on_goal = logical_and(on_goal, norm({x.name}_pos[:2] - first_{x.name}_pos[:2]) < {k['kept_m']})"
                   for x in others)
    plan.code.append(f'''def withdraw_up_done(tcp, touch, start_tcp, {n}_pos, {marker}_xy, {marker}_radius{kept}):
    """Up and away, the fingers off the object, the object left on the goal (one that slid off is not done), and
    every other object still where the attempt found it (a shoved one is not done)."""
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - start_tcp[2] - 0.08
    on_goal = logical_and(norm({n}_pos[:2] - {marker}_xy) < {marker}_radius, max(touch, axis=-1) < 0.1){left}
    return logical_and(sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015, on_goal)''')
    plan.stages += [
        StageSpec(name="carry", cost="carry_cost", done="carry_done", grip="closed", timeout_s=_t(k, 5.0)),
        StageSpec(name="lower", cost="lower_cost", done="lower_done", grip="closed", timeout_s=_t(k, 4.0)),
        StageSpec(name="release", cost="release_cost", done="release_done", grip="open", timeout_s=_t(k, 2.0)),
        StageSpec(name="withdraw", cost="withdraw_up_cost", done="withdraw_up_done", grip="open",
                  timeout_s=_t(k, 3.0)),
    ]
    plan.why.append(f"then carry it at {k['carry_z_m'] * 100:g} cm over '{marker}', lower it until it nearly "
                    "touches, open, and withdraw upward.")


def _gap(n: str, fixture: str, axis: int, sign: float) -> str:
    """Distance still to go until the object's leading side meets the fixture's near side (code expression)."""
    if sign > 0:
        return f"{fixture}_lo[{axis}] - {n}_hi[..., {axis}]"
    return f"{n}_lo[..., {axis}] - {fixture}_hi[{axis}]"


def _approach(plan: Plan, name: str, o: ObjectState, axis: int, sign: float, z_expr: str, back_m: float,
              k: dict[str, float]) -> None:
    """To a point behind the object's back face (along the push), at a height."""
    n = o.name
    other = 1 - axis
    face = f"start_{n}_lo[{axis}]" if sign > 0 else f"start_{n}_hi[{axis}]"
    plan.code.append(_sub(f'''def {name}_point(start_{n}_lo, start_{n}_hi, start_{n}_pos):
    return {face} - {sign} * ({k["paddle_m"]} + {back_m})


def {name}_cost(tcp, yaw, step_change, start_{n}_lo, start_{n}_hi, start_{n}_pos, {n}_half):
    """Behind the face to push, at the pushing height, hand square to the push."""
    ea = tcp[..., {axis}] - {name}_point(start_{n}_lo, start_{n}_hi, start_{n}_pos)
    eb = tcp[..., {other}] - start_{n}_pos[{other}]
    ez = tcp[..., 2] - ({z_expr})
    return W_REACH * sqrt(ea ** 2 + eb ** 2 + ez ** 2) + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def {name}_done(tcp, start_{n}_lo, start_{n}_hi, start_{n}_pos, {n}_half):
    ea = tcp[..., {axis}] - {name}_point(start_{n}_lo, start_{n}_hi, start_{n}_pos)
    eb = tcp[..., {other}] - start_{n}_pos[{other}]
    ez = tcp[..., 2] - ({z_expr})
    return sqrt(ea ** 2 + eb ** 2 + ez ** 2) < {k["reach_tol_m"] * 1.25 if back_m < 0.035 else k["reach_tol_m"]}''', k))


def _approach_blind(plan: Plan, name: str, o: ObjectState, k: dict[str, float]) -> None:
    """No contact strategy: go to the object (its centre); the planner has to find where to touch it."""
    n = o.name
    plan.code.append(_sub(f'''def {name}_cost(tcp, yaw, step_change, {n}_pos):
    return W_REACH * norm(tcp - {n}_pos) + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def {name}_done(tcp, {n}_pos, {n}_half):
    return norm(tcp - {n}_pos) < max({n}_half) + 0.03''', k))


def _touch_term(o: ObjectState, contact: bool, weight: str) -> tuple[str, str]:
    """(parameters, expression) pulling the TCP to the stage's contact region, or to the object without one."""
    if contact:
        return "contact", f"{weight} * contact"
    return f"{o.name}_pos", f"{weight} * norm(tcp - {o.name}_pos)"


def _push(plan: Plan, o: ObjectState, fixture: str, axis: int, sign: float, k: dict[str, float],
          contact: bool) -> None:
    n = o.name
    region = None
    if contact:
        plan.regions.append(back_face(o, axis, sign, None, k["push_z_m"] + 0.006, k))
        region = len(plan.regions) - 1
        _approach(plan, "approach", o, axis, sign, f"start_{n}_lo[2] + {k['push_z_m']}", 0.03, k)
    else:
        _approach_blind(plan, "approach", o, k)
    other = 1 - axis
    p, touch = _touch_term(o, contact, "W_CONTACT")
    plan.code.append(_sub(f'''def push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi):
    return {_gap(n, fixture, axis, sign)}


def push_cost(tcp, yaw, step_change, {p}, {n}_lo, {n}_hi, {n}_pos, {n}_vel, start_{n}_pos, {fixture}_lo, {fixture}_hi):
    """Slide it to the fixture: low on its back face, straight, not too fast."""
    gap = push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi)
    drift = abs({n}_pos[..., {other}] - start_{n}_pos[{other}])
    fast = relu(abs({n}_vel[..., {axis}]) - {k["push_speed_m_s"]})
    return (W_GAP * relu(gap) + {touch} + 5.0 * drift + 20.0 * fast + W_YAW * 0.5 * wrap_pi(yaw) ** 2
            + W_SMOOTH * step_change)


def push_done({n}_lo, {n}_hi, {n}_vel, {fixture}_lo, {fixture}_hi):
    return logical_and(push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi) < 0.002, norm({n}_vel) < 0.02)''', k))
    plan.stages += [
        StageSpec(name="approach", cost="approach_cost", done="approach_done", grip="closed", timeout_s=_t(k, 4.0)),
        StageSpec(name="push", cost="push_cost", done="push_done", grip="closed", region=region, hold_s=0.3,
                  timeout_s=_t(k, 5.0)),
    ]
    where = "low on the face turned away from it (it slides rather than tips)" if contact else "(no contact region)"
    plan.why.append(f"'{o.label}' is pushed against '{fixture}' with the closed fingers {where}.")


def _press(plan: Plan, o: ObjectState, fixture: str, axis: int, sign: float, force: float, k: dict[str, float],
           contact: bool) -> None:
    n = o.name
    p, touch = _touch_term(o, contact, "W_PRESS_CONTACT")
    hold = k["hold_press_s"]
    plan.code.append(_sub(f'''def press_cost(force, step_change, {p}, tcp, {n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi):
    """The target force, in units of a newton: a wrong force costs in proportion, so letting go never pays."""
    miss = abs({sign} * force[..., {axis}] - {force})
    gap = push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi)
    return W_FORCE * miss + {touch} + 100.0 * relu(gap) + W_SMOOTH * step_change


def press_done(force, {n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi):
    ok = abs({sign} * force[..., {axis}] - {force}) < {k["force_tol_n"]}
    return logical_and(ok, push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi) < 0.002)''', k))
    plan.stages.append(StageSpec(name="press", cost="press_cost", done="press_done", grip="closed",
                                 region=(len(plan.regions) - 1) if contact else None, hold_s=hold + 0.5,
                                 timeout_s=hold + 4.0, press_n=sign * force, press_axis=axis, noise_scale=0.15))
    plan.why.append(f"Then press with {force:g} N for {hold:g} s (force feedback at the inner rate, a small "
                    "sampling noise for fine regulation).")


def _tilt_code(n: str, deg: float) -> str:
    return f"{n}_up[..., 2] < {math.cos(math.radians(deg)):.6f}"


def _withdraw(plan: Plan, o: ObjectState, axis: int, sign: float, deg: float, k: dict[str, float], dz: float) -> None:
    n = o.name
    d = ["0.0", "0.0"]
    d[axis] = f"{-sign * 0.06}"
    plan.code.append(_sub(_hold_code("withdraw_cost", dx=d[0], dy=d[1], dz=str(dz)), k))
    plan.code.append(f'''def withdraw_done(tcp, start_tcp, {n}_up, {n}_vel, {n}_spin):
    ex = tcp[..., 0] - start_tcp[0] - {d[0]}
    ey = tcp[..., 1] - start_tcp[1] - {d[1]}
    ez = tcp[..., 2] - start_tcp[2] - {dz}
    away = sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015
    still = logical_and(norm({n}_vel) < 0.01, {n}_spin < 0.2)
    return logical_and(logical_and(away, still), {_tilt_code(n, deg)})''')
    plan.stages.append(StageSpec(name="withdraw", cost="withdraw_cost", done="withdraw_done", grip="closed",
                                 timeout_s=_t(k, 3.0)))


def _tip_cost(plan: Plan, name: str, o: ObjectState, edge: float, width: float, contact: bool,
              k: dict[str, float]) -> None:
    n = o.name
    p, touch = _touch_term(o, contact, "W_CONTACT")
    plan.code.append(_sub(f'''def {name}_cost(yaw, step_change, tcp, {p}, {n}_up):
    """Turn the object's up axis down; while it still stands, stay on the high contact region."""
    up = {n}_up[..., 2]
    standing = 1.0 / (1.0 + exp(-(up - {edge}) / {width / 3:.6f}))
    return W_TIP * up + {touch} * standing + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change''', k))


def _rise_and_turn(plan: Plan, o: ObjectState, axis: int, sign: float, k: dict[str, float], contact: bool,
                   names: tuple[str, str], back_m: float, edge: float, width: float, deg_key: str,
                   timeouts: tuple[float, float], withdraw_dz: float) -> None:
    """Shared by tip and pivot: go to the object's back face high up (or blindly to it), push there until its
    up axis has turned `k[deg_key]`, then withdraw and settle."""
    n = o.name
    rise, turn = names
    region = None
    if contact:
        plan.regions.append(back_face(o, axis, sign, k["push_height"], 0.0, k))
        region = len(plan.regions) - 1
        _approach(plan, rise, o, axis, sign, f"start_{n}_lo[2] + {k['push_height']} * 2.0 * {n}_half[2]",
                  back_m, k)
    else:
        _approach_blind(plan, rise, o, k)
    _tip_cost(plan, turn, o, edge, width, contact, k)
    plan.code.append(f'''def {turn}_done({n}_up):
    return {_tilt_code(n, k[deg_key])}''')
    plan.stages += [
        StageSpec(name=rise, cost=f"{rise}_cost", done=f"{rise}_done", grip="closed", timeout_s=_t(k, timeouts[0])),
        StageSpec(name=turn, cost=f"{turn}_cost", done=f"{turn}_done", grip="closed", region=region,
                  timeout_s=_t(k, timeouts[1])),
    ]
    _withdraw(plan, o, axis, sign, k["flip_deg"], k, withdraw_dz)
    _settle(plan, "settle", 0.3, "closed", k)


def _tip(plan: Plan, o: ObjectState, axis: int, sign: float, k: dict[str, float], contact: bool) -> None:
    _rise_and_turn(plan, o, axis, sign, k, contact, ("approach", "tip"), 0.04, 0.75, 0.1, "tip_deg", (4.0, 5.0), 0.06)
    plan.why.append(f"'{o.label}' stands taller than it is wide: push it high on its back "
                    f"({'at ' + str(k['push_height']) + ' of its height' if contact else 'no contact region'}) "
                    f"until it tips past {k['tip_deg']:g} deg, then draw the hand back and let it settle.")


def _pivot(plan: Plan, o: ObjectState, fixture: str, axis: int, sign: float, k: dict[str, float],
           contact: bool) -> None:
    """Push the flat object against the fixture, then high on its back until it has turned well past upright
    (`pivot_deg`): it falls on over the fixture instead of coming to rest balanced on the fixture's top. The hand
    never reaches more than `reach_over_m` past the fixture's face and does not fling the object; then it rises
    straight off (fingertips resting on the turned object would drag it back over the fixture), draws back, and
    the attempt counts as done only when the object rests turned, still and on the table (not on the fixture)."""
    n = o.name
    _push(plan, o, fixture, axis, sign, {**k, "timeout_scale": k["timeout_scale"]}, contact)
    plan.stages[-1] = plan.stages[-1].model_copy(update={"hold_s": 0.2})
    plan.why.pop()
    region = None
    if contact:
        plan.regions.append(back_face(o, axis, sign, k["push_height"], 0.0, k))
        region = len(plan.regions) - 1
        _approach(plan, "rise", o, axis, sign, f"start_{n}_lo[2] + {k['push_height']} * 2.0 * {n}_half[2]",
                  0.035, k)
    else:
        _approach_blind(plan, "rise", o, k)
    p, touch = _touch_term(o, contact, "W_CONTACT")
    face = f"{fixture}_lo[{axis}]" if sign > 0 else f"{fixture}_hi[{axis}]"
    plan.code.append(_sub(f'''def pivot_cost(yaw, step_change, tcp, {p}, {n}_up, {n}_vel, {fixture}_lo, {fixture}_hi):
    """Turn the object's up axis over; while it still lies low, stay on the high contact region. The hand never
    reaches far past the fixture's face, and the object is not flung over it."""
    up = {n}_up[..., 2]
    standing = 1.0 / (1.0 + exp(-(up - 0.5) / {0.2 / 3:.6f}))
    over = relu({sign} * (tcp[..., {axis}] - {face}) - {k["reach_over_m"]})
    fling = relu(norm({n}_vel) - {k["fling_m_s"]})
    return (W_TIP * up + {touch} * standing + 100.0 * over + 20.0 * fling + W_YAW * 0.5 * wrap_pi(yaw) ** 2
            + W_SMOOTH * step_change)


def pivot_done({n}_up):
    return {_tilt_code(n, k["pivot_deg"])}


def turned_still({n}_up, {n}_vel, {n}_spin):
    """Turned at least `flip_deg` and at rest."""
    still = logical_and(norm({n}_vel) < 0.01, {n}_spin < 0.2)
    return logical_and(still, {_tilt_code(n, k["flip_deg"])})


def on_table({n}_lo, {fixture}_lo):
    """Down on the table the fixture stands on, not resting on the fixture's top."""
    return {n}_lo[2] < {fixture}_lo[2] + {k["rest_m"]}''', k))
    plan.code.append(_sub(_hold_code("lift_off_cost", dz="0.05", seed=True), k))
    plan.code.append('''def lift_off_done(tcp, start_tcp):
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - start_tcp[2] - 0.05
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.012''')
    d = ["0.0", "0.0"]
    d[axis] = f"{-sign * 0.06}"
    plan.code.append(_sub(_hold_code("withdraw_cost", dx=d[0], dy=d[1], seed=True), k))
    plan.code.append(f'''def withdraw_done(tcp, start_tcp, {n}_up, {n}_vel, {n}_spin):
    ex = tcp[..., 0] - start_tcp[0] - {d[0]}
    ey = tcp[..., 1] - start_tcp[1] - {d[1]}
    ez = tcp[..., 2] - start_tcp[2]
    away = sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015
    return logical_and(away, turned_still({n}_up, {n}_vel, {n}_spin))''')
    # an object that came to rest on the fixture's top is pushed on, over the fixture's far side, to the table
    near_end, back = (f"{n}_lo", "-") if sign > 0 else (f"{n}_hi", "+")
    far = f"{fixture}_hi[{axis}]" if sign > 0 else f"{fixture}_lo[{axis}]"
    other = 1 - axis
    plan.code.append(_sub(f'''def clear_cost(tcp, yaw, step_change, {n}_lo, {n}_hi, {n}_pos, {fixture}_lo, {fixture}_hi):
    """Behind the object's near end at its centre's height, pushing until its centre is past the fixture's far
    side (it then drops off the fixture onto the table); the hand never reaches far past the fixture's face."""
    ea = tcp[..., {axis}] - ({near_end}[..., {axis}] {back} {k["paddle_m"]})
    eb = tcp[..., {other}] - {n}_pos[..., {other}]
    ez = tcp[..., 2] - {n}_pos[..., 2]
    off = relu({sign} * ({far} - {n}_pos[..., {axis}]) + 0.01)
    over = relu({sign} * (tcp[..., {axis}] - {face}) - {k["reach_over_m"]})
    return (W_GAP * off + W_CONTACT * sqrt(ea ** 2 + eb ** 2 + ez ** 2) + 100.0 * over
            + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change)


def clear_done({n}_lo, {fixture}_lo):
    return on_table({n}_lo, {fixture}_lo)''', k))
    plan.code.append(_sub(_hold_code("back_cost", dx=d[0], dy=d[1], seed=True), k))
    plan.code.append(f'''def back_done(tcp, start_tcp, {n}_lo, {n}_hi):
    """Drawn back, or already well clear of the object's near end (nothing was pushed)."""
    ex = tcp[..., 0] - start_tcp[0] - {d[0]}
    ey = tcp[..., 1] - start_tcp[1] - {d[1]}
    ez = tcp[..., 2] - start_tcp[2]
    away = sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015
    clear = {sign} * ({near_end}[{axis}] - tcp[{axis}]) > 0.04
    return logical_or(away, clear)''')
    plan.code.append(_sub(_hold_code("settle_cost"), k))
    plan.code.append(f'''def settle_done({n}_up, {n}_vel, {n}_spin, {n}_lo, {fixture}_lo):
    return logical_and(turned_still({n}_up, {n}_vel, {n}_spin), on_table({n}_lo, {fixture}_lo))''')
    plan.stages += [
        StageSpec(name="rise", cost="rise_cost", done="rise_done", grip="closed", timeout_s=_t(k, 4.0)),
        StageSpec(name="pivot", cost="pivot_cost", done="pivot_done", grip="closed", region=region,
                  timeout_s=_t(k, 6.0)),
        StageSpec(name="lift-off", cost="lift_off_cost", done="lift_off_done", grip="closed", noise_scale=0.4,
                  timeout_s=_t(k, 2.0)),
        StageSpec(name="withdraw", cost="withdraw_cost", done="withdraw_done", grip="closed", timeout_s=_t(k, 3.0)),
        StageSpec(name="clear", cost="clear_cost", done="clear_done", grip="closed", timeout_s=_t(k, 4.0)),
        StageSpec(name="back", cost="back_cost", done="back_done", grip="closed", timeout_s=_t(k, 2.0)),
        StageSpec(name="settle", cost="settle_cost", done="settle_done", grip="closed", hold_s=1.0,
                  timeout_s=_t(k, 3.0)),
    ]
    plan.why.append(f"'{o.label}' lies flat and '{fixture}' stops its far edge: push it against '{fixture}', "
                    f"then push high on its back so it pivots over the fixture past {k['pivot_deg']:g} deg "
                    f"(well past upright, so it neither falls back nor stays balanced on top of '{fixture}'), "
                    "lift the hand straight off, draw it back, push it on off the fixture's top if it came to rest there, "
                    "and count it done only when the object rests "
                    f"turned past {k['flip_deg']:g} deg, still, and down on the table.")


def _push_over_edge(plan: Plan, o: ObjectState, k: dict[str, float], contact: bool) -> None:
    """Slide a flat object toward the table's front edge (+x) until its far end sticks out `overhang_m`:
    enough for the fingers to pinch it `pinch_past_edge_m` beyond the edge, with room to spare."""
    n = o.name
    region = None
    if contact:
        plan.regions.append(back_face(o, 0, 1.0, None, k["push_z_m"] + 0.006, k))
        region = len(plan.regions) - 1
        _approach(plan, "approach", o, 0, 1.0, f"start_{n}_lo[2] + {k['push_z_m']}", 0.03, k)
    else:
        _approach_blind(plan, "approach", o, k)
    p, touch = _touch_term(o, contact, "W_CONTACT")
    plan.code.append(_sub(f'''def overhang({n}_hi, table_edge_x):
    """How far the object's far end sticks out past the table edge."""
    return {n}_hi[..., 0] - table_edge_x


def edge_push_cost(tcp, yaw, step_change, {p}, {n}_hi, {n}_pos, {n}_vel, start_{n}_pos, table_edge_x):
    """Slide it out until the far end overhangs enough, low on its back face, straight, slowly, and no further."""
    out = overhang({n}_hi, table_edge_x)
    drift = abs({n}_pos[..., 1] - start_{n}_pos[1])
    fast = relu(abs({n}_vel[..., 0]) - {k["push_speed_m_s"] / 2})
    return (W_GAP * relu({k["overhang_m"]} - out) + 100.0 * relu(out - {k["overhang_m"] + 0.01}) + {touch}
            + 5.0 * drift + 20.0 * fast + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change)


def edge_push_done({n}_hi, {n}_vel, table_edge_x):
    return logical_and(overhang({n}_hi, table_edge_x) > {k["overhang_m"] - 0.005}, norm({n}_vel) < 0.01)''', k))
    plan.code.append(_sub(_hold_code("back_off_cost", dx="-0.03", dz=f"({k['travel_z_m']} - start_tcp[2])", yaw="0.0",
                                     seed=True), k))
    plan.code.append(f'''def back_off_done(tcp, start_tcp):
    ex = tcp[..., 0] - start_tcp[0] + 0.03
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - {k["travel_z_m"]}
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015''')
    plan.stages += [
        StageSpec(name="approach", cost="approach_cost", done="approach_done", grip="closed", timeout_s=_t(k, 4.0)),
        StageSpec(name="push", cost="edge_push_cost", done="edge_push_done", grip="closed", region=region, hold_s=0.2,
                  timeout_s=_t(k, 9.0)),
        StageSpec(name="back-off", cost="back_off_cost", done="back_off_done", grip="closed", timeout_s=_t(k, 3.0)),
    ]
    where = "low on its back face" if contact else "(no contact region)"
    plan.why.append(f"'{o.label}' is slid toward the table's front edge with the closed fingers {where} until its far "
                    f"end sticks out {k['overhang_m'] * 100:g} cm, slowly (a shoved board coasts on), then the hand "
                    f"backs off and rises to {k['travel_z_m'] * 100:g} cm.")


def _pick_past_edge(plan: Plan, o: ObjectState, k: dict[str, float]) -> None:
    """Pinch the overhanging end from below the table top, beyond the edge, with the hand across it, and lift."""
    n = o.name
    past, under, travel = k["pinch_past_edge_m"], k["under_edge_z_m"], k["travel_z_m"]
    plan.code.append(_sub(f'''def pinch_y(start_{n}_pos, start_{n}_yaw, table_edge_x):
    """Where the object's long axis crosses the line the pinch goes on, beyond the edge."""
    return start_{n}_pos[1] + (table_edge_x + {past} - start_{n}_pos[0]) * tan(start_{n}_yaw)


def over_end_cost(tcp, yaw, step_change, start_{n}_pos, start_{n}_yaw, table_edge_x):
    """Above the overhanging end, turned across it, never low over the object (it must not be swept along)."""
    ex = tcp[..., 0] - table_edge_x - {past}
    ey = tcp[..., 1] - pinch_y(start_{n}_pos, start_{n}_yaw, table_edge_x)
    ez = tcp[..., 2] - {travel}
    return (W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + 30.0 * wrap_pi(yaw - start_{n}_yaw) ** 2
            + 200.0 * relu({travel - 0.02} - tcp[..., 2]) + W_SMOOTH * step_change)


def over_end_done(tcp, yaw, tcp_vel, start_{n}_pos, start_{n}_yaw, table_edge_x):
    """There, turned, and no longer moving (a hand still swinging in comes down beside the pinch point)."""
    ex = tcp[..., 0] - table_edge_x - {past}
    ey = tcp[..., 1] - pinch_y(start_{n}_pos, start_{n}_yaw, table_edge_x)
    ez = tcp[..., 2] - {travel}
    there = logical_and(sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.01, abs(wrap_pi(yaw - start_{n}_yaw)) < 0.05)
    return logical_and(there, norm(tcp_vel) < {k["still_m_s"]})


def over_end_cost_seed_x(table_edge_x):
    return table_edge_x + {past}


def over_end_cost_seed_y(start_{n}_pos, start_{n}_yaw, table_edge_x):
    return pinch_y(start_{n}_pos, start_{n}_yaw, table_edge_x)


def over_end_cost_seed_z(start_tcp):
    return {travel} + 0.0 * start_tcp[2]


def over_end_cost_seed_yaw(start_{n}_yaw):
    return start_{n}_yaw


def under_cost(tcp, yaw, step_change, start_tcp, start_yaw):
    """Straight down past the edge until the fingertips are below the object's underside."""
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - ({under})
    exy = sqrt(ex ** 2 + ey ** 2)
    return W_REACH * sqrt(exy ** 2 + ez ** 2) + 2.0 * W_REACH * exy + 30.0 * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def under_cost_seed_x(start_tcp):
    return start_tcp[0]


def under_cost_seed_y(start_tcp):
    return start_tcp[1]


def under_cost_seed_z(start_tcp):
    return {under} + 0.0 * start_tcp[2]


def under_done(tcp, tcp_vel, start_tcp):
    """Down and stopped: fingers that close while the hand still sinks drag the handle down, and the board
    levers up over the table edge."""
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - ({under})
    return logical_and(sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.006, norm(tcp_vel) < {k["still_m_s"]})''', k))
    plan.code.append(_sub(_hold_code("pinch_cost", w_yaw="30.0", seed=True), k))
    plan.code.append(f'''def pinch_done(touch):
    return min(touch, axis=-1) > {k["edge_touch_n"]}''')
    plan.code.append(_sub(f'''def lift_end_cost(tcp, yaw, step_change, start_tcp, start_yaw, {n}_pos, start_{n}_pos):
    """Up and a little back over the table, with the object: a penalty while it lags below."""
    ex = tcp[..., 0] - start_tcp[0] + 0.03
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - {k["edge_lift_z_m"]}
    lag = relu(start_{n}_pos[2] + {k["edge_lift_z_m"] - 0.05} - {n}_pos[..., 2])
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + W_REACH * lag + 30.0 * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def lift_end_cost_seed_x(start_tcp):
    return start_tcp[0] - 0.03


def lift_end_cost_seed_y(start_tcp):
    return start_tcp[1]


def lift_end_cost_seed_z(start_tcp):
    return {k["edge_lift_z_m"]} + 0.0 * start_tcp[2]


def lift_end_done(tcp, touch, start_tcp):
    ex = tcp[..., 0] - start_tcp[0] + 0.03
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - {k["edge_lift_z_m"]}
    return logical_and(sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015, min(touch, axis=-1) > 1.0)''', k))
    plan.code.append(_sub(_hold_code("still_cost", w_yaw="30.0", seed=True), k))
    plan.code.append(f'''def still_done({n}_vel, {n}_spin):
    return logical_and(norm({n}_vel) < 0.015, {n}_spin < 0.2)''')
    plan.stages += [
        StageSpec(name="reach", cost="over_end_cost", done="over_end_done", grip="open", noise_scale=0.35,
                  timeout_s=_t(k, 4.0)),
        StageSpec(name="descend", cost="under_cost", done="under_done", grip="open", noise_scale=0.35,
                  timeout_s=_t(k, 3.0)),
        StageSpec(name="grasp", cost="pinch_cost", done="pinch_done", grip="closed", hold_s=0.3, noise_scale=0.35,
                  timeout_s=_t(k, 2.0)),
        StageSpec(name="lift", cost="lift_end_cost", done="lift_end_done", grip="closed", timeout_s=_t(k, 4.0)),
        StageSpec(name="hold", cost="still_cost", done="still_done", grip="closed", hold_s=0.3, noise_scale=0.25,
                  timeout_s=_t(k, 8.0)),
    ]
    plan.why.append(f"Then reach above the overhanging end {past * 100:g} cm past the edge with the open hand turned "
                    f"across it, go down until the fingertips are {-under * 100:g} cm below the table top, close until "
                    f"both pads press {k['edge_touch_n']:g} N, lift to {k['edge_lift_z_m'] * 100:g} cm and hold still.")
