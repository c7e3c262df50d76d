"""Pick an object (the side that fits the gripper, clear of its neighbours) and put it down on a marker.
"""

from __future__ import annotations

from kintsugi.methods.coral.costlib.templates import Plan, hold_code, timeout, with_weights
from kintsugi.methods.coral.types import ObjectState, StageSpec


def pick(plan: Plan, o: ObjectState, others: list[ObjectState], k: dict[str, float], contact: bool = True) -> None:
    """Grasp across the side that fits, clear of the neighbours, at a pinch height from the finger length; lift.
    Without a contact strategy the grasp is the planner's to find: the hand keeps its yaw and closes around the
    object's centre."""
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
    grasp_z = "maximum(0.006, {n}_half[2] - finger_length / 3.0)" if contact else "{n}_half[2] + 0.0 * finger_length"
    plan.code.append(f'''def {n}_open({n}_half, max_opening):
    """Open just wider than the object's wider horizontal side (either side may be the one pinched)."""
    return minimum(max_opening, 2.0 * maximum({n}_half[0], {n}_half[1]) + 0.035)


def {n}_grasp_z({n}_half, finger_length):
    return {grasp_z.format(n=n)}''')
    if contact:
        plan.code.append(f'''def {n}_aim({params}):
    """The hand yaw to pinch with, chosen once when the stage begins (the variable `kept`)."""
{side}
    return aim''')
    else:
        plan.code.append(f'''def {n}_aim(start_yaw):
    """No grasp strategy: the hand keeps the yaw it has."""
    return start_yaw''')
    plan.code.append(with_weights(f'''def reach_cost(tcp, yaw, step_change, {n}_pos, start_{n}_hi, kept):
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
    plan.code.append(with_weights(hold_code("grasp_cost"), k))
    plan.code.append(f'''def grasp_done(touch):
    return min(touch, axis=-1) > {k["touch_n"]}''')
    plan.code.append(with_weights(f'''def lift_cost(tcp, yaw, step_change, start_tcp, start_yaw, {n}_pos, start_{n}_pos):
    """Up, with the object: a penalty while the object lags below the lift height."""
    ex = tcp[..., 0] - start_tcp[0]
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - start_tcp[2] - {k["lift_m"]}
    lag = relu(start_{n}_pos[2] + {k["lift_m"]} - {n}_pos[..., 2])
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + 2.0 * W_REACH * lag + W_YAW * wrap_pi(yaw - start_yaw) ** 2 + W_SMOOTH * step_change


def lift_done(touch, {n}_pos, start_{n}_pos, {n}_lo):
    """Lifted: the object's lowest point (its tracked pose and known shape) clear of the table, both pads on it."""
    up = logical_and({n}_pos[..., 2] > start_{n}_pos[2] + {k["lift_m"] - 0.02}, {n}_lo[..., 2] > {k["clear_lift_m"]})
    return logical_and(up, min(touch, axis=-1) > 0.5)''', k))
    plan.stages += [
        StageSpec(name="reach", cost="reach_cost", done="reach_done", grip=f"{n}_open", keep=f"{n}_aim",
                  timeout_s=timeout(k, 5.0)),
        # restarted at the grasp point with fine sampling noise (as the expert's descent): centimetre jitter here
        # puts a finger on an edge and shoves the object or a neighbour away
        StageSpec(name="descend", cost="descend_cost", done="descend_done", grip=f"{n}_open", noise_scale=0.35,
                  timeout_s=timeout(k, 4.0)),
        StageSpec(name="grasp", cost="grasp_cost", done="grasp_done", grip="closed", hold_s=0.2,
                  timeout_s=timeout(k, 2.0)),
        StageSpec(name="lift", cost="lift_cost", done="lift_done", grip="closed", timeout_s=timeout(k, 4.0)),
    ]
    plan.why.append(f"'{o.label}' is picked: reach above it with the hand turned across a side that fits the "
                    f"gripper{' and clear of ' + ', '.join(x.label for x in others) if others else ''}, descend, "
                    f"close until both pads press {k['touch_n']:g} N, lift {k['lift_m'] * 100:g} cm.")


def place(plan: Plan, o: ObjectState, others: list[ObjectState], marker: str, k: dict[str, float]) -> None:
    n = o.name
    plan.code.append(with_weights(f'''def carry_cost(tcp, yaw, step_change, start_tcp, start_yaw, {n}_pos, start_{n}_pos, {marker}_xy):
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
    plan.code.append(with_weights(hold_code("release_cost"), k))
    plan.code.append('''def release_done(opening, touch, max_opening):
    return logical_and(opening > 0.8 * max_opening, max(touch, axis=-1) < 0.1)''')
    plan.code.append(with_weights(hold_code("withdraw_up_cost", dz="0.08"), k))
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
        StageSpec(name="carry", cost="carry_cost", done="carry_done", grip="closed", timeout_s=timeout(k, 5.0)),
        StageSpec(name="lower", cost="lower_cost", done="lower_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="release", cost="release_cost", done="release_done", grip="open", timeout_s=timeout(k, 2.0)),
        StageSpec(name="withdraw", cost="withdraw_up_cost", done="withdraw_up_done", grip="open",
                  timeout_s=timeout(k, 3.0)),
    ]
    plan.why.append(f"then carry it at {k['carry_z_m'] * 100:g} cm over '{marker}', lower it until it nearly "
                    "touches, open, and withdraw upward.")
