"""Push an object against a fixture, low on the face turned away from it, and press it there with a force.
"""

from __future__ import annotations

from kintsugi.methods.coral.costlib.templates import (Plan, approach, approach_blind, gap_expr, timeout, touch_term,
                                                 with_weights)
from kintsugi.methods.coral.costlib.scene import back_face
from kintsugi.methods.coral.types import ObjectState, StageSpec


def push(plan: Plan, o: ObjectState, fixture: str, axis: int, sign: float, k: dict[str, float],
          contact: bool) -> None:
    n = o.name
    region = None
    if contact:
        plan.regions.append(back_face(o, axis, sign, None, k["push_z_m"] + 0.006, k))
        region = len(plan.regions) - 1
        approach(plan, "approach", o, axis, sign, f"start_{n}_lo[2] + {k['push_z_m']}", 0.03, k)
    else:
        approach_blind(plan, "approach", o, k)
    other = 1 - axis
    p, touch = touch_term(o, contact, "W_CONTACT")
    plan.code.append(with_weights(f'''def push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi):
    return {gap_expr(n, fixture, axis, sign)}


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
        StageSpec(name="approach", cost="approach_cost", done="approach_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="push", cost="push_cost", done="push_done", grip="closed", region=region, hold_s=0.3,
                  timeout_s=timeout(k, 5.0)),
    ]
    where = "low on the face turned away from it (it slides rather than tips)" if contact else "(no contact region)"
    plan.why.append(f"'{o.label}' is pushed against '{fixture}' with the closed fingers {where}.")


def press(plan: Plan, o: ObjectState, fixture: str, axis: int, sign: float, force: float, k: dict[str, float],
           contact: bool) -> None:
    n = o.name
    p, touch = touch_term(o, contact, "W_PRESS_CONTACT")
    hold = k["hold_press_s"]
    plan.code.append(with_weights(f'''def press_cost(force, step_change, {p}, tcp, {n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi):
    """The target force, in units of a newton: a wrong force costs in proportion, so letting go never pays."""
    miss = abs({sign} * force[..., {axis}] - {force})
    gap = push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi)
    return W_FORCE * miss + {touch} + 100.0 * relu(gap) + W_SMOOTH * step_change


def press_done(force, {n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi):
    ok = abs({sign} * force[..., {axis}] - {force}) < {k["force_tol_n"]}
    return logical_and(ok, push_gap({n}_lo, {n}_hi, {fixture}_lo, {fixture}_hi) < 0.002)''', k))
    plan.stages.append(StageSpec(name="press", cost="press_cost", done="press_done", grip="closed",
                                 region=(len(plan.regions) - 1) if contact else None, hold_s=hold + 0.2,
                                 timeout_s=hold + 4.0, press_n=sign * force, press_axis=axis, noise_scale=0.15))
    plan.why.append(f"Then press with {force:g} N for {hold:g} s (force feedback at the inner rate, a small "
                    "sampling noise for fine regulation).")
