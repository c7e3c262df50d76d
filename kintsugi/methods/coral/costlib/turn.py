"""Turn an object over: tip a tall one by pushing high on its back, or pivot a flat one over a fixture.
"""

from __future__ import annotations

import math

from kintsugi.methods.coral.costlib.templates import (Plan, approach, approach_blind, hold_code, settle, tilt_code,
                                                 timeout, touch_term, with_weights)
from kintsugi.methods.coral.costlib.push import push
from kintsugi.methods.coral.costlib.scene import back_face
from kintsugi.methods.coral.types import ObjectState, StageSpec

FLAT_DEG = 6.0
"""A turned object is at rest only lying on a face: its up axis within this of vertical or level (twice the
tracker's tilt error on a resting box)."""


def _withdraw(plan: Plan, o: ObjectState, axis: int, sign: float, deg: float, k: dict[str, float], dz: float) -> None:
    n = o.name
    d = ["0.0", "0.0"]
    d[axis] = f"{-sign * 0.06}"
    plan.code.append(with_weights(hold_code("withdraw_cost", dx=d[0], dy=d[1], dz=str(dz)), k))
    plan.code.append(f'''def withdraw_done(tcp, start_tcp, {n}_up, {n}_vel, {n}_spin):
    ex = tcp[..., 0] - start_tcp[0] - {d[0]}
    ey = tcp[..., 1] - start_tcp[1] - {d[1]}
    ez = tcp[..., 2] - start_tcp[2] - {dz}
    away = sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015
    still = logical_and(norm({n}_vel) < 0.01, {n}_spin < 0.2)
    return logical_and(logical_and(away, still), {tilt_code(n, deg)})''')
    plan.stages.append(StageSpec(name="withdraw", cost="withdraw_cost", done="withdraw_done", grip="closed",
                                 timeout_s=timeout(k, 3.0)))


def _tip_cost(plan: Plan, name: str, o: ObjectState, edge: float, width: float, contact: bool,
              k: dict[str, float]) -> None:
    n = o.name
    p, touch = touch_term(o, contact, "W_CONTACT")
    plan.code.append(with_weights(f'''def {name}_cost(yaw, step_change, tcp, {p}, {n}_up):
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
        approach(plan, rise, o, axis, sign, f"start_{n}_lo[2] + {k['push_height']} * 2.0 * {n}_half[2]",
                  back_m, k)
    else:
        approach_blind(plan, rise, o, k)
    _tip_cost(plan, turn, o, edge, width, contact, k)
    plan.code.append(f'''def {turn}_done({n}_up):
    return {tilt_code(n, k[deg_key])}''')
    plan.stages += [
        StageSpec(name=rise, cost=f"{rise}_cost", done=f"{rise}_done", grip="closed", timeout_s=timeout(k, timeouts[0])),
        StageSpec(name=turn, cost=f"{turn}_cost", done=f"{turn}_done", grip="closed", region=region,
                  timeout_s=timeout(k, timeouts[1])),
    ]
    _withdraw(plan, o, axis, sign, k["flip_deg"], k, withdraw_dz)
    settle(plan, "settle", 0.3, "closed", k)


def tip(plan: Plan, o: ObjectState, axis: int, sign: float, k: dict[str, float], contact: bool) -> None:
    _rise_and_turn(plan, o, axis, sign, k, contact, ("approach", "tip"), 0.04, 0.75, 0.1, "tip_deg", (4.0, 5.0), 0.06)
    plan.why.append(f"'{o.label}' stands taller than it is wide: push it high on its back "
                    f"({'at ' + str(k['push_height']) + ' of its height' if contact else 'no contact region'}) "
                    f"until it tips past {k['tip_deg']:g} deg, then draw the hand back and let it settle.")


def pivot(plan: Plan, o: ObjectState, fixture: str, axis: int, sign: float, k: dict[str, float],
           contact: bool) -> None:
    """Push the flat object against the fixture, then high on its back until it has turned well past upright
    (`pivot_deg`): it falls on over the fixture instead of coming to rest balanced on the fixture's top. The hand
    never reaches more than `reach_over_m` past the fixture's face and does not fling the object; then it rises
    straight off (fingertips resting on the turned object would drag it back over the fixture), draws back, and
    the attempt counts as done only when the object rests turned, still and on the table (not on the fixture)."""
    n = o.name
    push(plan, o, fixture, axis, sign, {**k, "timeout_scale": k["timeout_scale"]}, contact)
    plan.stages[-1] = plan.stages[-1].model_copy(update={"hold_s": 0.2})
    plan.why.pop()
    region = None
    if contact:
        plan.regions.append(back_face(o, axis, sign, k["push_height"], 0.0, k))
        region = len(plan.regions) - 1
        approach(plan, "rise", o, axis, sign, f"start_{n}_lo[2] + {k['push_height']} * 2.0 * {n}_half[2]",
                  0.035, k)
    else:
        approach_blind(plan, "rise", o, k)
    p, touch = touch_term(o, contact, "W_CONTACT")
    face = f"{fixture}_lo[{axis}]" if sign > 0 else f"{fixture}_hi[{axis}]"
    plan.code.append(with_weights(f'''def pivot_cost(yaw, step_change, tcp, {p}, {n}_up, {n}_vel, {fixture}_lo, {fixture}_hi):
    """Turn the object's up axis over; while it still lies low, stay on the high contact region. The hand never
    reaches far past the fixture's face, and the object is not flung over it."""
    up = {n}_up[..., 2]
    standing = 1.0 / (1.0 + exp(-(up - 0.5) / {0.2 / 3:.6f}))
    over = relu({sign} * (tcp[..., {axis}] - {face}) - {k["reach_over_m"]})
    fling = relu(norm({n}_vel) - {k["fling_m_s"]})
    return (W_TIP * up + {touch} * standing + 100.0 * over + 20.0 * fling + W_YAW * 0.5 * wrap_pi(yaw) ** 2
            + W_SMOOTH * step_change)


def pivot_done({n}_up):
    return {tilt_code(n, k["pivot_deg"])}


def turned_still({n}_up, {n}_vel, {n}_spin):
    """Turned at least `flip_deg` and at rest, lying on a face: its up axis vertical or level within
    {FLAT_DEG:g} degrees. An object propped at a slant (one end on the fixture) creeps at a few mm/s, which
    the camera's velocity cannot tell from rest."""
    still = logical_and(norm({n}_vel) < 0.01, {n}_spin < 0.2)
    flat = logical_or(abs({n}_up[..., 2]) > {math.cos(math.radians(FLAT_DEG)):.6f}, abs({n}_up[..., 2]) < {math.sin(math.radians(FLAT_DEG)):.6f})
    return logical_and(logical_and(still, flat), {tilt_code(n, k["flip_deg"])})


def on_table({n}_lo, {fixture}_lo):
    """Down on the table the fixture stands on, not resting on the fixture's top."""
    return {n}_lo[2] < {fixture}_lo[2] + {k["rest_m"]}''', k))
    plan.code.append(with_weights(hold_code("lift_off_cost", dz="0.05", seed=True), k))
    plan.code.append('''def lift_off_done(tcp, start_tcp):
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - start_tcp[2] - 0.05
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.012''')
    d = ["0.0", "0.0"]
    d[axis] = f"{-sign * 0.06}"
    plan.code.append(with_weights(hold_code("withdraw_cost", dx=d[0], dy=d[1], seed=True), k))
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
    plan.code.append(with_weights(f'''def clear_cost(tcp, yaw, step_change, {n}_lo, {n}_hi, {n}_pos, {fixture}_lo, {fixture}_hi):
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
    plan.code.append(with_weights(hold_code("back_cost", dx=d[0], dy=d[1], seed=True), k))
    plan.code.append(f'''def back_done(tcp, start_tcp, {n}_lo, {n}_hi):
    """Drawn back, or already well clear of the object's near end (nothing was pushed)."""
    ex = tcp[..., 0] - start_tcp[0] - {d[0]}
    ey = tcp[..., 1] - start_tcp[1] - {d[1]}
    ez = tcp[..., 2] - start_tcp[2]
    away = sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015
    clear = {sign} * ({near_end}[{axis}] - tcp[{axis}]) > 0.04
    return logical_or(away, clear)''')
    plan.code.append(with_weights(hold_code("settle_cost"), k))
    plan.code.append(f'''def settle_done({n}_up, {n}_vel, {n}_spin, {n}_lo, {fixture}_lo):
    return logical_and(turned_still({n}_up, {n}_vel, {n}_spin), on_table({n}_lo, {fixture}_lo))''')
    plan.stages += [
        StageSpec(name="rise", cost="rise_cost", done="rise_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="pivot", cost="pivot_cost", done="pivot_done", grip="closed", region=region,
                  timeout_s=timeout(k, 6.0)),
        StageSpec(name="lift-off", cost="lift_off_cost", done="lift_off_done", grip="closed", noise_scale=0.4,
                  timeout_s=timeout(k, 2.0)),
        StageSpec(name="withdraw", cost="withdraw_cost", done="withdraw_done", grip="closed", timeout_s=timeout(k, 3.0)),
        StageSpec(name="clear", cost="clear_cost", done="clear_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="back", cost="back_cost", done="back_done", grip="closed", timeout_s=timeout(k, 2.0)),
        StageSpec(name="settle", cost="settle_cost", done="settle_done", grip="closed", hold_s=1.0,
                  timeout_s=timeout(k, 3.0)),
    ]
    plan.why.append(f"'{o.label}' lies flat and '{fixture}' stops its far edge: push it against '{fixture}', "
                    f"then push high on its back so it pivots over the fixture past {k['pivot_deg']:g} deg "
                    f"(well past upright, so it neither falls back nor stays balanced on top of '{fixture}'), "
                    "lift the hand straight off, draw it back, push it on off the fixture's top if it came to rest there, "
                    "and count it done only when the object rests "
                    f"turned past {k['flip_deg']:g} deg, still, and down on the table.")
