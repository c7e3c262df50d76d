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

ROUND = ("cylinder", "sphere", "ball", "puck", "can", "disc", "capsule")


Point = tuple
"""Where a leg starts or ends: ("first", dx, dy) = where the object was when the attempt began, plus an offset;
("marker", name) = a marker's centre; ("point", x, y) = a point on the table (a way point beside an obstacle)."""


def _xy(n: str, p: Point) -> tuple[str, str, list[str]]:
    """(x, y, parameters) of a point as code."""
    if p[0] == "first":
        return f"first_{n}_pos[0] + {float(p[1])!r}", f"first_{n}_pos[1] + {float(p[2])!r}", [f"first_{n}_pos"]
    if p[0] == "marker":
        return f"{p[1]}_xy[0]", f"{p[1]}_xy[1]", [f"{p[1]}_xy"]
    return f"{float(p[1])!r} + 0.0 * start_{n}_yaw", f"{float(p[2])!r} + 0.0 * start_{n}_yaw", [f"start_{n}_yaw"]


def _plist(*groups: list[str] | str) -> str:
    out: list[str] = []
    for g in groups:
        for x in ([g] if isinstance(g, str) else g):
            if x and x not in out:
                out.append(x)
    return ", ".join(out)


def avoid_code(n: str, fixtures: list[str], o: ObjectState) -> str:
    """Functions giving the clearance of the object (its footprint's radius) and of the fingers from each fixture to
    avoid: the distance from a point to the fixture's box, as a penalty inside the clearance."""
    r = math.hypot(o.size_m[0], o.size_m[1]) / 2 + 0.01
    out = []
    for f in fixtures:
        for who, name, clear in ((f"{n}_pos", f"clear_{f}_{n}", r), ("tcp", f"clear_{f}_hand", 0.025)):
            out.append(f'''def {name}({who}, {f}_lo, {f}_hi):
    """How far inside {clear:.3f} m of {f} (its footprint's circle) the point is (0 when clear)."""
    dx = {who}[..., 0] - 0.5 * ({f}_lo[0] + {f}_hi[0])
    dy = {who}[..., 1] - 0.5 * ({f}_lo[1] + {f}_hi[1])
    reach = {clear:.4f} + 0.5 * sqrt(({f}_hi[0] - {f}_lo[0]) ** 2 + ({f}_hi[1] - {f}_lo[1]) ** 2)
    return relu(reach - sqrt(dx * dx + dy * dy))''')
    return "\n\n\n".join(out)


def _avoid_terms(n: str, fixtures: list[str]) -> tuple[list[str], str]:
    params, terms = [], []
    for f in fixtures:
        params += [f"{f}_lo", f"{f}_hi"]
        terms += [f"300.0 * clear_{f}_{n}({n}_pos, {f}_lo, {f}_hi)", f"300.0 * clear_{f}_hand(tcp, {f}_lo, {f}_hi)"]
    return params, (" + " + " + ".join(terms)) if terms else ""


def _support(o: ObjectState) -> str:
    """Distance from the object's centre to its face along the push (ux, uy), as code of its yaw and half extents."""
    n = o.name
    if round_(o):
        return f"{n}_half[0] + 0.0 * ux"
    return (f"abs(ux * cos(start_{n}_yaw) + uy * sin(start_{n}_yaw)) * {n}_half[0]"
            f" + abs(uy * cos(start_{n}_yaw) - ux * sin(start_{n}_yaw)) * {n}_half[1]")


def _region(o: ObjectState, ux: float, uy: float, k: dict[str, float]) -> RegionSpec:
    """The contact region on the face turned away from the goal, in the object's frame: low on a box (it slides
    rather than tips), through the middle of a round object (it rolls)."""
    yaw = math.radians(o.yaw_deg)
    lx, ly = math.cos(yaw) * ux + math.sin(yaw) * uy, -math.sin(yaw) * ux + math.cos(yaw) * uy
    half = [s / 2 for s in o.size_m]
    if round_(o):
        cx, cy = -lx * half[0], -ly * half[0]
    else:
        sup = abs(lx) * half[0] + abs(ly) * half[1]
        cx, cy = max(-half[0], min(half[0], -lx * sup)), max(-half[1], min(half[1], -ly * sup))
    return RegionSpec(object=o.name, center=(cx, cy, _push_z(o, k) - half[2]), normal=(-lx, -ly, 0.0), radius=0.008,
                      standoff=k["paddle_m"], drop=0.006)


def round_(o: ObjectState) -> bool:
    return (o.shape or "").lower() in ROUND


def _push_z(o: ObjectState, k: dict[str, float]) -> float:
    """Height above the object's bottom the fingers push at."""
    if round_(o) and o.size_m[2] <= min(o.size_m[0], o.size_m[1]) * 1.05:  # it rolls or slides, it cannot tip
        return o.size_m[2] / 2
    return min(k["push_z_m"] + 0.006, o.size_m[2] / 2)


def slide(plan: Plan, o: ObjectState, req: FormulationRequest, k: dict[str, float], contact: bool,
          origin: Point, goal: Point, avoid: list[str] = (), tol_m: float | None = None) -> None:
    """One leg: from `origin` (where the object is when the leg begins) to `goal`."""
    n = o.name
    here = {"marker": {m.name: (m.x_m, m.y_m) for m in req.markers}}
    ox, oy, op = _xy(n, origin)
    gx, gy, gp = _xy(n, goal)
    # the push direction at formulation (for the region); the code computes it from the variables
    def num(p: Point) -> tuple[float, float]:
        if p[0] == "first":
            return o.pos_m[0] + p[1], o.pos_m[1] + p[2]
        if p[0] == "marker":
            return here["marker"][p[1]]
        return p[1], p[2]
    (a, b), (c, d) = num(origin), num(goal)
    length0 = math.hypot(c - a, d - b) or 1.0
    region = None
    if contact:
        plan.regions.append(_region(o, (c - a) / length0, (d - b) / length0, k))
        region = len(plan.regions) - 1
    if goal[0] == "marker":
        tol, tp = f"0.5 * {goal[1]}_radius", [f"{goal[1]}_radius"]
    else:
        tol, tp = repr(tol_m or 0.012), []
    line = _plist(op, gp)
    fixed = "point" in (origin[0], goal[0])
    """A leg to or from a way point (a constant of this scene) has a constant direction: written as numbers."""
    u_of = {"x": f"slide_ux({line})", "y": f"slide_uy({line})"}
    if fixed:
        u_of = {"x": repr(round((c - a) / length0, 6)), "y": repr(round((d - b) / length0, 6))}
    lets = f"""    ux = {u_of["x"]}
    uy = {u_of["y"]}"""
    args = _plist(op, [f"start_{n}_yaw", f"{n}_half"], gp)
    if len(args.split(", ")) > 4:  # pragma: no cover - points take at most one variable each
        raise ValueError("a leg's points take too many variables")
    av_params, av = _avoid_terms(n, list(avoid))
    touch = "W_CONTACT * contact" if contact else f"W_CONTACT * norm(tcp - {n}_pos)"
    touch_p = "contact" if contact else f"{n}_pos"
    units = "\n\n\n".join(f'''def slide_u{a_}({line}):
    dx = ({gx}) - ({ox})
    dy = ({gy}) - ({oy})
    return d{a_} / (sqrt(dx ** 2 + dy ** 2) + 1e-9)''' for a_ in "xy")
    behind = "\n\n\n".join(f'''def slide_p{a_}({args}):
    return ({(ox, oy)[i]}) - {u_of[a_]} * slide_back({args})''' for i, a_ in enumerate("xy"))
    if fixed:
        units = ""
    behind = f'''{units}{"" if fixed else chr(10) * 3}def slide_back({args}):
    """How far behind the object's centre the fingers start: its support along the push, and a margin."""
{lets}
    return {_support(o)} + {k["paddle_m"] + 0.03}


{behind}'''
    z = _push_z(o, k)
    code = f'''{behind}


def over_cost(tcp, yaw, step_change, {_plist(args, f"start_{n}_hi", av_params)}):
    """Above the point behind the object, clear of its top."""
    ex = tcp[..., 0] - slide_px({args})
    ey = tcp[..., 1] - slide_py({args})
    ez = tcp[..., 2] - start_{n}_hi[2] - {k["clear_m"]}
    return W_REACH * sqrt(ex ** 2 + ey ** 2 + ez ** 2) + W_HALF_YAW * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def over_done(tcp, {_plist(args, f"start_{n}_hi")}):
    ex = tcp[..., 0] - slide_px({args})
    ey = tcp[..., 1] - slide_py({args})
    ez = tcp[..., 2] - start_{n}_hi[2] - {k["clear_m"]}
    return sqrt(ex ** 2 + ey ** 2 + ez ** 2) < {k["reach_tol_m"] * 1.5}


def down_cost(tcp, yaw, step_change, {_plist(args, f"start_{n}_lo")}):
    """Straight down behind the face to the pushing height."""
    exy = sqrt((tcp[..., 0] - slide_px({args})) ** 2 + (tcp[..., 1] - slide_py({args})) ** 2)
    ez = tcp[..., 2] - start_{n}_lo[2] - {z!r}
    return W_REACH * (sqrt(exy ** 2 + ez ** 2) + 2.0 * exy) + W_HALF_YAW * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change


def down_cost_seed_x({args}):
    return slide_px({args})


def down_cost_seed_y({args}):
    return slide_py({args})


def down_cost_seed_z(start_{n}_lo):
    return start_{n}_lo[2] + {z!r}


def down_done(tcp, {_plist(args, f"start_{n}_lo")}):
    exy = sqrt((tcp[..., 0] - slide_px({args})) ** 2 + (tcp[..., 1] - slide_py({args})) ** 2)
    ez = tcp[..., 2] - start_{n}_lo[2] - {z!r}
    return sqrt(exy ** 2 + ez ** 2) < {k["reach_tol_m"]}


def slide_cost(tcp, yaw, step_change, {_plist(touch_p, f"{n}_pos", f"{n}_vel", op, gp, [f"start_{n}_yaw"] if "start_" in ox + gx else [], av_params)}):
    """The object to the goal along the line from where the leg began, slowly, never past the goal."""
{lets}
    length = sqrt((({gx}) - ({ox})) ** 2 + (({gy}) - ({oy})) ** 2)
    ox = {n}_pos[..., 0] - ({ox})
    oy = {n}_pos[..., 1] - ({oy})
    along = ox * ux + oy * uy
    ahead = (tcp[..., 0] - {n}_pos[..., 0]) * ux + (tcp[..., 1] - {n}_pos[..., 1]) * uy
    speed = {n}_vel[..., 0] * ux + {n}_vel[..., 1] * uy
    return (W_GAP * relu(length - along) + 100.0 * relu(along - length - 0.005) + 20.0 * abs(oy * ux - ox * uy)
            + {touch} + 20.0 * relu(abs(speed) - {k["push_speed_m_s"]}) + 20.0 * relu(ahead)
            + W_HALF_YAW * wrap_pi(yaw) ** 2 + W_SMOOTH * step_change{av})


def slide_there({_plist(f"{n}_pos", gp, tp)}):
    return sqrt(({n}_pos[0] - ({gx})) ** 2 + ({n}_pos[1] - ({gy})) ** 2) < {tol}


def slide_done({_plist(f"{n}_pos", f"{n}_vel", gp, tp)}):
    return logical_and(slide_there({_plist(f"{n}_pos", gp, tp)}), norm({n}_vel) < 0.01)'''
    plan.code.append(with_weights(code.replace("W_HALF_YAW", repr(round(k["w_yaw"] / 2, 6))), k))
    final = goal[0] != "point"
    if final:
        plan.code.append(with_weights(hold_code("leave_cost", dz="0.06", seed=True), k))
        plan.code.append(f'''def leave_done({_plist("tcp", "start_tcp", f"{n}_pos", f"{n}_vel", gp, tp)}):
    """Up off the object, which is still on the goal and at rest."""
    ez = tcp[..., 2] - start_tcp[2] - 0.06
    exy = sqrt((tcp[..., 0] - start_tcp[0]) ** 2 + (tcp[..., 1] - start_tcp[1]) ** 2)
    there = logical_and(slide_there({_plist(f"{n}_pos", gp, tp)}), norm({n}_vel) < 0.01)
    return logical_and(sqrt(exy ** 2 + ez ** 2) < 0.015, there)''')
    plan.stages += [
        StageSpec(name="over", cost="over_cost", done="over_done", grip="closed", timeout_s=timeout(k, 4.0)),
        StageSpec(name="down", cost="down_cost", done="down_done", grip="closed", noise_scale=0.5,
                  timeout_s=timeout(k, 3.0)),
        StageSpec(name="slide", cost="slide_cost", done="slide_done", grip="closed", region=region, hold_s=0.3,
                  timeout_s=timeout(k, 8.0)),
    ] + ([StageSpec(name="leave", cost="leave_cost", done="leave_done", grip="closed", timeout_s=timeout(k, 3.0))]
         if final else [])  # at a way point the next leg's move over the object lifts the hand
    to = {"marker": lambda: f"onto '{goal[1]}'", "first": lambda: f"to {math.hypot(goal[1], goal[2]) * 100:.0f} cm from "
          "where it began", "point": lambda: f"to the way point ({goal[1]:.3f}, {goal[2]:.3f})"}[goal[0]]()
    where = ("through its middle (it rolls)" if round_(o) else "low on the face turned away from the goal") \
        if contact else "(no contact region)"
    clear = f", clear of {', '.join(avoid)}" if avoid else ""
    plan.why.append(f"'{o.label}' is slid {to} with the closed fingers {where}{clear}: over it, down behind it, a "
                    "slow push on the line from where it began with no overshoot, then the hand rises off.")
