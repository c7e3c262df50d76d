"""Slide a flat object out over the table's front edge, then pinch the overhanging end from below and lift it.
"""

from __future__ import annotations

from kintsugi.methods.coral.costlib.templates import (Plan, approach, approach_blind, hold_code, timeout, touch_term,
                                                 with_weights)
from kintsugi.methods.coral.costlib.scene import back_face
from kintsugi.methods.coral.types import ObjectState, StageSpec


def push_over_edge(plan: Plan, o: ObjectState, k: dict[str, float], contact: bool) -> None:
    """Slide a flat object toward the table's front edge (+x) until its far end sticks out `overhang_m`:
    enough for the fingers to pinch it `pinch_past_edge_m` beyond the edge, with room to spare."""
    n = o.name
    region = None
    if contact:
        plan.regions.append(back_face(o, 0, 1.0, None, k["push_z_m"] + 0.006, k))
        region = len(plan.regions) - 1
        approach(plan, "approach", o, 0, 1.0, f"start_{n}_lo[2] + {k['push_z_m']}", 0.03, k)
    else:
        approach_blind(plan, "approach", o, k)
    p, touch = touch_term(o, contact, "W_CONTACT")
    plan.code.append(with_weights(f'''def overhang({n}_hi, table_edge_x):
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
    plan.code.append(with_weights(hold_code("back_off_cost", dx="-0.03", dz=f"({k['travel_z_m']} - start_tcp[2])", yaw="0.0",
                                     seed=True), k))
    plan.code.append(f'''def back_off_done(tcp, start_tcp):
    ex = tcp[..., 0] - start_tcp[0] + 0.03
    ey = tcp[..., 1] - start_tcp[1]
    ez = tcp[..., 2] - {k["travel_z_m"]}
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < 0.015''')
    plan.stages += [
        StageSpec(name="approach", cost="approach_cost", done="approach_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="push", cost="edge_push_cost", done="edge_push_done", grip="closed", region=region, hold_s=0.2,
                  timeout_s=timeout(k, 9.0)),
        StageSpec(name="back-off", cost="back_off_cost", done="back_off_done", grip="closed", timeout_s=timeout(k, 3.0)),
    ]
    where = "low on its back face" if contact else "(no contact region)"
    plan.why.append(f"'{o.label}' is slid toward the table's front edge with the closed fingers {where} until its far "
                    f"end sticks out {k['overhang_m'] * 100:g} cm, slowly (a shoved board coasts on), then the hand "
                    f"backs off and rises to {k['travel_z_m'] * 100:g} cm.")


def pick_past_edge(plan: Plan, o: ObjectState, k: dict[str, float]) -> None:
    """Pinch the overhanging end from below the table top, beyond the edge, with the hand across it, and lift."""
    n = o.name
    past, under, travel = k["pinch_past_edge_m"], k["under_edge_z_m"], k["travel_z_m"]
    plan.code.append(with_weights(f'''def pinch_y(start_{n}_pos, start_{n}_yaw, table_edge_x):
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
    plan.code.append(with_weights(hold_code("pinch_cost", w_yaw="30.0", seed=True), k))
    plan.code.append(f'''def pinch_done(touch):
    return min(touch, axis=-1) > {k["edge_touch_n"]}''')
    plan.code.append(with_weights(f'''def lift_end_cost(tcp, yaw, step_change, start_tcp, start_yaw, {n}_pos, start_{n}_pos):
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
    plan.code.append(with_weights(hold_code("still_cost", w_yaw="30.0", seed=True), k))
    plan.code.append(f'''def still_done({n}_vel, {n}_spin, {n}_lo, touch):
    """At rest in the hand, and lifted: the object's lowest point (a sagging end included) clear of the table,
    both pads on it."""
    held = logical_and({n}_lo[..., 2] > {k["clear_lift_m"]}, min(touch, axis=-1) > 0.5)
    return logical_and(logical_and(norm({n}_vel) < 0.015, {n}_spin < 0.2), held)''')
    plan.stages += [
        StageSpec(name="reach", cost="over_end_cost", done="over_end_done", grip="open", noise_scale=0.35,
                  timeout_s=timeout(k, 4.0)),
        StageSpec(name="descend", cost="under_cost", done="under_done", grip="open", noise_scale=0.35,
                  timeout_s=timeout(k, 3.0)),
        StageSpec(name="grasp", cost="pinch_cost", done="pinch_done", grip="closed", hold_s=0.3, noise_scale=0.35,
                  timeout_s=timeout(k, 2.0)),
        StageSpec(name="lift", cost="lift_end_cost", done="lift_end_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="hold", cost="still_cost", done="still_done", grip="closed", hold_s=0.3, noise_scale=0.25,
                  timeout_s=timeout(k, 8.0)),
    ]
    plan.why.append(f"Then reach above the overhanging end {past * 100:g} cm past the edge with the open hand turned "
                    f"across it, go down until the fingertips are {-under * 100:g} cm below the table top, close until "
                    f"both pads press {k['edge_touch_n']:g} N, lift to {k['edge_lift_z_m'] * 100:g} cm and hold still.")
