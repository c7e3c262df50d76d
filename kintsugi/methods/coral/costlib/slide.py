"""Push an object along the table to a goal with nothing to stop it: onto a marker, or a distance in a direction.

Primitives: approach the face turned away from the goal (over the object, then down behind it, so the hand never
sweeps through it), push on it low toward the goal (slowly, on the line from where it started, no overshoot), and
withdraw up and back. The goal and the push direction are expressions of the variables the code reads (the
marker's centre, where the object was when the attempt began), so stored code fits a new scene. Round objects
(a cylinder standing, a sphere) are pushed at their radius; boxes at the support of their footprint along the push.
"""

from __future__ import annotations

import math

from kintsugi.methods.coral.costlib.templates import Plan, hold_code, timeout, with_weights
from kintsugi.methods.coral.types import FormulationRequest, ObjectState, RegionSpec, StageSpec

ROUND = ("cylinder", "sphere", "ball", "puck", "can", "disc")


def _goal(n: str, marker: str | None, axis: int, sign: float, distance: float | None) -> tuple[str, str, str]:
    """(parameters, goal x, goal y) as code."""
    if marker is not None:
        return f"{marker}_xy", f"{marker}_xy[0]", f"{marker}_xy[1]"
    d = [0.0, 0.0]
    d[axis] = sign * float(distance or 0.0)
    return f"first_{n}_pos", f"first_{n}_pos[0] + {d[0]!r}", f"first_{n}_pos[1] + {d[1]!r}"


def _support(o: ObjectState) -> str:
    """Distance from the object's centre to its face along the push (u), as code of ux, uy and its yaw."""
    n = o.name
    if (o.shape or "").lower() in ROUND:
        return f"{n}_half[0]"
    return (f"abs(ux * cos(start_{n}_yaw) + uy * sin(start_{n}_yaw)) * {n}_half[0]"
            f" + abs(uy * cos(start_{n}_yaw) - ux * sin(start_{n}_yaw)) * {n}_half[1]")


def _region(o: ObjectState, req: FormulationRequest, marker: str | None, axis: int, sign: float,
            k: dict[str, float]) -> RegionSpec:
    """The contact region on the face turned away from the goal, low, in the object's frame."""
    if marker is not None:
        m = next(x for x in req.markers if x.name == marker)
        ux, uy = m.x_m - o.pos_m[0], m.y_m - o.pos_m[1]
    else:
        ux, uy = (sign, 0.0) if axis == 0 else (0.0, sign)
    length = math.hypot(ux, uy) or 1.0
    ux, uy = ux / length, uy / length
    yaw = math.radians(o.yaw_deg)
    lx, ly = math.cos(yaw) * ux + math.sin(yaw) * uy, -math.sin(yaw) * ux + math.cos(yaw) * uy
    half = [s / 2 for s in o.size_m]
    if (o.shape or "").lower() in ROUND:
        cx, cy = -lx * half[0], -ly * half[0]
    else:
        sup = abs(lx) * half[0] + abs(ly) * half[1]
        cx, cy = -lx * sup, -ly * sup
        cx, cy = max(-half[0], min(half[0], cx)), max(-half[1], min(half[1], cy))
    z = -half[2] + min(k["push_z_m"] + 0.006, half[2])
    return RegionSpec(object=o.name, center=(cx, cy, z), normal=(-lx, -ly, 0.0), radius=0.008,
                      standoff=k["paddle_m"], drop=0.006)


def slide(plan: Plan, o: ObjectState, req: FormulationRequest, k: dict[str, float], contact: bool,
          marker: str | None = None, axis: int = 0, sign: float = 1.0, distance: float | None = None) -> None:
    n = o.name
    gp, gx, gy = _goal(n, marker, axis, sign, distance)
    region = None
    if contact:
        plan.regions.append(_region(o, req, marker, axis, sign, k))
        region = len(plan.regions) - 1
    tol = f"0.5 * {marker}_radius" if marker is not None else "0.012"
    tol_params = f", {marker}_radius" if marker is not None else ""
    if marker is not None:
        lets = f"""    dx = ({gx}) - first_{n}_pos[0]
    dy = ({gy}) - first_{n}_pos[1]
    length = sqrt(dx ** 2 + dy ** 2) + 1e-9
    ux = dx / length
    uy = dy / length"""
    else:
        u = [0.0, 0.0]
        u[axis] = sign
        lets = f"""    ux = {u[0]!r}
    uy = {u[1]!r}
    length = {float(distance or 0.0)!r}"""
    gparams = "" if gp == f"first_{n}_pos" else f", {gp}"
    touch = "W_CONTACT * contact" if contact else f"W_CONTACT * norm(tcp - {n}_pos)"
    touch_p = "contact" if contact else f"{n}_pos"
    behind = "\n\n\n".join(f'''def slide_p{a}(first_{n}_pos, start_{n}_yaw, {n}_half{gparams}):
    """{a} of the point behind the object's face turned away from the goal."""
{lets}
    back = {_support(o)} + {k["paddle_m"] + 0.03}
    return first_{n}_pos[{i}] - u{a} * back''' for i, a in enumerate("xy"))
    args = f"first_{n}_pos, start_{n}_yaw, {n}_half{gparams}"
    code = f'''{behind}


def over_cost(tcp, yaw, step_change, {args}, start_{n}_hi):
    """Above the point behind the object, clear of its top."""
    ex = tcp[..., 0] - slide_px({args})
    ey = tcp[..., 1] - slide_py({args})
    ez = tcp[..., 2] - start_{n}_hi[2] - {k["clear_m"]}
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def over_done(tcp, {args}, start_{n}_hi):
    ex = tcp[..., 0] - slide_px({args})
    ey = tcp[..., 1] - slide_py({args})
    ez = tcp[..., 2] - start_{n}_hi[2] - {k["clear_m"]}
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < {k["reach_tol_m"] * 1.5}


def down_cost(tcp, yaw, step_change, {args}, start_{n}_lo):
    """Straight down behind the face to the pushing height."""
    exy = sqrt((tcp[..., 0] - slide_px({args})) ** 2 + (tcp[..., 1] - slide_py({args})) ** 2)
    ez = tcp[..., 2] - start_{n}_lo[2] - {k["push_z_m"]}
    return W_REACH * sqrt(exy ** 2 + ez ** 2) + 2.0 * W_REACH * exy + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def down_done(tcp, {args}, start_{n}_lo):
    exy = sqrt((tcp[..., 0] - slide_px({args})) ** 2 + (tcp[..., 1] - slide_py({args})) ** 2)
    ez = tcp[..., 2] - start_{n}_lo[2] - {k["push_z_m"]}
    return sqrt(exy ** 2 + ez ** 2) < {k["reach_tol_m"]}


def slide_cost(tcp, yaw, step_change, {touch_p}, {n}_pos, {n}_vel, first_{n}_pos{gparams}):
    """The object to the goal along the line it started on, slowly, never past the goal."""
{lets}
    ox = {n}_pos[..., 0] - first_{n}_pos[0]
    oy = {n}_pos[..., 1] - first_{n}_pos[1]
    along = ox * ux + oy * uy
    ahead = (tcp[..., 0] - {n}_pos[..., 0]) * ux + (tcp[..., 1] - {n}_pos[..., 1]) * uy
    speed = {n}_vel[..., 0] * ux + {n}_vel[..., 1] * uy
    return (W_GAP * relu(length - along) + 100.0 * relu(along - length - 0.005) + 5.0 * abs(oy * ux - ox * uy)
            + {touch} + 20.0 * relu(abs(speed) - {k["push_speed_m_s"]}) + 20.0 * relu(ahead)
            + W_YAW * 0.5 * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change)


def slide_there({n}_pos, first_{n}_pos{gparams}{tol_params}):
    """On the goal (within the tolerance)."""
    return sqrt(({n}_pos[0] - ({gx})) ** 2 + ({n}_pos[1] - ({gy})) ** 2) < {tol}


def slide_done({n}_pos, {n}_vel, first_{n}_pos{gparams}{tol_params}):
    """There and at rest."""
    return logical_and(slide_there({n}_pos, first_{n}_pos{gparams}{tol_params}), norm({n}_vel) < 0.01)'''
    plan.code.append(with_weights(code, k))
    plan.code.append(with_weights(hold_code("leave_cost", dz="0.06", seed=True), k))
    plan.code.append(f'''def leave_done(tcp, start_tcp, {n}_pos, {n}_vel, first_{n}_pos{gparams}{tol_params}):
    """Up off the object, which is still on the goal and at rest."""
    ez = tcp[..., 2] - start_tcp[2] - 0.06
    exy = sqrt((tcp[..., 0] - start_tcp[0]) ** 2 + (tcp[..., 1] - start_tcp[1]) ** 2)
    there = logical_and(slide_there({n}_pos, first_{n}_pos{gparams}{tol_params}), norm({n}_vel) < 0.01)
    return logical_and(sqrt(exy ** 2 + ez ** 2) < 0.015, there)''')
    plan.stages += [
        StageSpec(name="over", cost="over_cost", done="over_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="down", cost="down_cost", done="down_done", grip="closed", noise_scale=0.5,
                  timeout_s=timeout(k, 3.0)),
        StageSpec(name="slide", cost="slide_cost", done="slide_done", grip="closed", region=region, hold_s=0.3,
                  timeout_s=timeout(k, 8.0)),
        StageSpec(name="leave", cost="leave_cost", done="leave_done", grip="closed", timeout_s=timeout(k, 3.0)),
    ]
    goal = f"onto '{marker}'" if marker is not None else f"{distance * 100:g} cm along {'xy'[axis]}{sign:+g}"  # type: ignore[operator]
    where = "low on the face turned away from the goal" if contact else "(no contact region)"
    plan.why.append(f"'{o.label}' is slid {goal} with the closed fingers {where}: over it, down behind it, a slow "
                    "push on the line it started on with no overshoot, then the hand rises off.")
