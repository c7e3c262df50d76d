"""The pieces every skill writes its stages with: the knobs, the plan being built, and cost-code templates.

Costs are strings of the cost language (kintsugi.sandbox). Weights appear as placeholders (`W_REACH`, ...)
that `with_weights` fills from the knobs; thresholds are written in as numbers when the code is built.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from kintsugi.methods.coral.types import ObjectState, RegionSpec, StageSpec


DEFAULT_KNOBS: dict[str, float] = {
    "w_reach": 10.0, "w_smooth": 50.0, "w_yaw": 1.0, "w_contact": 10.0, "w_gap": 30.0, "w_force": 3.0,
    "w_press_contact": 300.0, "w_tip": 5.0,
    "clear_m": 0.025, "lift_m": 0.12, "carry_z_m": 0.14, "set_down_m": 0.004, "touch_n": 2.0,
    "push_z_m": 0.008, "push_height": 0.7, "paddle_m": 0.01, "push_speed_m_s": 0.08,
    "tip_deg": 45.0, "pivot_deg": 125.0, "reach_over_m": 0.06, "fling_m_s": 0.3, "rest_m": 0.005, "flip_deg": 75.0, "reach_tol_m": 0.012, "force_tol_n": 0.6,
    "timeout_scale": 1.0, "hold_press_s": 2.0,
    "overhang_m": 0.09, "pinch_past_edge_m": 0.035, "under_edge_z_m": -0.012, "travel_z_m": 0.07,
    "edge_lift_z_m": 0.28, "edge_touch_n": 5.0, "still_m_s": 0.03, "kept_m": 0.02, "clear_lift_m": 0.06,
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


def timeout(k: dict[str, float], s: float) -> float:
    return round(s * k["timeout_scale"], 3)


def hold_code(name: str, dx: str = "0.0", dy: str = "0.0", dz: str = "0.0", yaw: str = "start_yaw",
               extra: str = "", w_yaw: str = "W_YAW", seed: bool = False) -> str:
    """A cost holding the TCP at start_tcp + (dx, dy, dz) with a yaw; with `seed`, the plan restarts there."""
    code = f'''def {name}(tcp, yaw, step_change, start_tcp, start_yaw{extra}):
    ex = tcp[..., 0] - start_tcp[0] - {dx}
    ey = tcp[..., 1] - start_tcp[1] - {dy}
    ez = tcp[..., 2] - start_tcp[2] - {dz}
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + {w_yaw} * wrap_pi(yaw - {yaw}) ** 2 + W_SMOOTH * step_change'''
    if seed:
        code += "\n\n\n" + seed_code(name, "start_tcp, start_yaw", f"start_tcp[0] + {dx}", f"start_tcp[1] + {dy}",
                                        f"start_tcp[2] + {dz}", yaw)
    return code


def seed_code(cost: str, params: str, x: str, y: str, z: str, yaw: str | None = None) -> str:
    """The stage's goal as the commands its plan restarts from (`<cost>_seed_<axis>`, read at stage entry):
    the servos head straight for it and MPPI refines from there, instead of crawling from the last plan."""
    axes = [("x", x), ("y", y), ("z", z)] + ([("yaw", yaw)] if yaw is not None else [])
    return "\n\n\n".join(f'''def {cost}_seed_{a}({params}):
    return {v}''' for a, v in axes)


def with_weights(code: str, k: dict[str, float]) -> str:
    for key in ("w_reach", "w_smooth", "w_yaw", "w_contact", "w_gap", "w_force", "w_press_contact", "w_tip"):
        code = code.replace(key.upper(), repr(round(k[key], 6)))
    return code


def settle(plan: Plan, name: str, seconds: float, grip: str, k: dict[str, float]) -> None:
    fn = f"{name}_cost"
    plan.code.append(with_weights(hold_code(fn), k))
    plan.code.append(f'''def {name}_done(tcp):
    return 1.0 + 0.0 * tcp[..., 0]''')
    plan.stages.append(StageSpec(name=name, cost=fn, done=f"{name}_done", grip=grip, hold_s=seconds,
                                 timeout_s=seconds + 2.0))


def gap_expr(n: str, fixture: str, axis: int, sign: float) -> str:
    """Distance still to go until the object's leading side meets the fixture's near side (code expression)."""
    if sign > 0:
        return f"{fixture}_lo[{axis}] - {n}_hi[..., {axis}]"
    return f"{n}_lo[..., {axis}] - {fixture}_hi[{axis}]"


def approach(plan: Plan, name: str, o: ObjectState, axis: int, sign: float, z_expr: str, back_m: float,
              k: dict[str, float]) -> None:
    """To a point behind the object's back face (along the push), at a height."""
    n = o.name
    other = 1 - axis
    face = f"start_{n}_lo[{axis}]" if sign > 0 else f"start_{n}_hi[{axis}]"
    plan.code.append(with_weights(f'''def {name}_point(start_{n}_lo, start_{n}_hi, start_{n}_pos):
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


def approach_blind(plan: Plan, name: str, o: ObjectState, k: dict[str, float]) -> None:
    """No contact strategy: go to the object (its centre); the planner has to find where to touch it."""
    n = o.name
    plan.code.append(with_weights(f'''def {name}_cost(tcp, yaw, step_change, {n}_pos):
    return W_REACH * norm(tcp - {n}_pos) + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def {name}_done(tcp, {n}_pos, {n}_half):
    return norm(tcp - {n}_pos) < max({n}_half) + 0.03''', k))


def touch_term(o: ObjectState, contact: bool, weight: str) -> tuple[str, str]:
    """(parameters, expression) pulling the TCP to the stage's contact region, or to the object without one."""
    if contact:
        return "contact", f"{weight} * contact"
    return f"{o.name}_pos", f"{weight} * norm(tcp - {o.name}_pos)"


def tilt_code(n: str, deg: float) -> str:
    return f"{n}_up[..., 2] < {math.cos(math.radians(deg)):.6f}"
