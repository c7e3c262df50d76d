"""Expert costs for T1 push-pick-board: push the board's back edge with the closed fingers until the
handle overhangs the table edge, then pinch the overhanging handle with the fingertips below the board
and lift it clear.

FSM: approach behind the plate, low -> push until the handle sticks out `PUSH_OVERHANG_M` (and the board
has stopped) -> back off and rise -> reach above the handle past the edge, turned across it -> descend
below the board -> close -> lift -> hold. Single stage: one cost whose pick terms switch on smoothly as
the predicted overhang passes the pickable minimum (the paper's Listing 1 "soft switch").
"""

from __future__ import annotations

import math

import numpy as np

from kintsugi.worlds.contact.config import PushPickBoardConfig
from kintsugi.worlds.contact.context import ContactContext
from kintsugi.methods.mppi.costs import Attractor, ContactRegion, View, norm, smoothness, step_up, total, yaw_error
from kintsugi.methods.expert.designs.common import W_SMOOTH, hold_tcp, near, settle
from kintsugi.methods.expert.designs.picking import DESCEND_NOISE
from kintsugi.worlds.contact.objects import Geometry
from kintsugi.methods.mppi.fsm import Stage, StageFactory
from kintsugi.worlds.contact.push_pick_board import overhang
from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.world import yaw_of

PUSH_Z = 0.004
"""Fingertip height while pushing the plate's back edge."""
PADDLE = 0.01
PUSH_MARGIN_M = 0.025
"""Pushed this far past the pickable minimum overhang (scoring-independent: the expert's own margin)."""
GRASP_PAST_EDGE_M = 0.035
"""The pinch's centre this far beyond the table edge: the fingers (2 cm wide) clear it."""
GRASP_Z = -0.012
"""Fingertips below the board's bottom: the pads cover the handle's whole thickness."""
LIFT_Z = 0.28
TRAVEL_Z = 0.07
"""Fingertip height for moving over the board (its top is about 2 cm up)."""
GRASP_TOUCH_N = 5.0
YAW_W = 30.0
PUSH_SPEED = 0.05
PUSH_TIMEOUT_S = 9.0
"""The farthest start (8 cm from the edge) plus the 9.5 cm overhang is 17 cm at PUSH_SPEED behind a lagging
servo; 6 s ran out on the two farthest starts of ten."""
PUSH_LEAD_M = 0.004
"""How far ahead of the contact point the pushing TCP aims (a few newtons through the servo)."""
PUSH_NOISE = 0.5
"""Half the sampling noise while pushing: at full noise (3 cm std on x, 2 cm on y) the weighted mean of the
samples hovers behind the plate near the end of the push (the lead a slow push needs is lost in the spread),
and the push stalls a centimetre short of its target."""
MAX_PRESS_N = 3.0
PRESS_W = 0.1
"""Cost per newton the fingertips press on the table beyond MAX_PRESS_N (predicted wrist force). Without it
the z command drifts down where the cost is flat (the table stops the fingertips), the fingers grind into
the table with 15-25 N and drag on it with the pads' friction: the x servo saturates, the push stick-slips,
and the board's own friction (about 1.5 N) is lost under the drag. (A floor on the z command instead biased
the samples' mean upwards: the approach then hovered 2 cm above its target.)"""


def _hold(target: np.ndarray, yaw: float, floor: float | None = None):  # noqa: ANN202 - a cost
    """hold_tcp with a firm yaw: a hand that wobbles about z shakes a board held by its handle. With
    `floor`, the fingertips keep above that height on the way (they must not sweep the board along)."""
    base = hold_tcp(target, None)

    def cost(v: View) -> np.ndarray:
        run = YAW_W * yaw_error(v.yaw, yaw) ** 2
        if floor is not None:
            run = run + 200 * np.maximum(0.0, floor - v.tcp[..., 2])
        return base(v) + total(run)

    return cost


def pressing(v: View) -> np.ndarray:
    """(K, T) running cost of pushing down on the table harder than MAX_PRESS_N."""
    return PRESS_W * np.maximum(0.0, -v.force[..., 2] - MAX_PRESS_N)


def _seed(target: np.ndarray, yaw: float | None = None) -> dict[int, float]:
    """Restart the plan's x, y, z (and yaw) commands at a stage's target: MPPI refines from there."""
    out = {i: float(target[i]) for i in range(3)}
    return out | ({3: yaw} if yaw is not None else {})


def back_region(ctx: ContactContext) -> ContactRegion:
    """The plate's -x edge, low: where the closed fingers push."""
    geo = ctx.known.geometry["board"]
    hx, _, hz = geo.parts[0].half
    return ContactRegion(obj="board", center=(-hx, 0.0, 0.0), normal=(-1.0, 0.0, 0.0), radius=0.01,
                         standoff=PADDLE, drop=hz - PUSH_Z)


def _handle_region(ctx: ContactContext) -> ContactRegion:
    """The handle's top, across its whole length (drawn; the grasp point itself is chosen at the edge)."""
    h = ctx.known.geometry["board"].parts[1]
    return ContactRegion(obj="board", center=(h.pos[0] + h.half[0] / 2, 0.0, h.half[2]), normal=(0.0, 0.0, 1.0),
                         radius=h.half[0] / 2)


def grasp_point(pos: np.ndarray, quat: np.ndarray, edge_x: float, geo: Geometry) -> tuple[np.ndarray, float]:
    """(point on the handle's axis, board yaw) where the pinch goes: GRASP_PAST_EDGE_M beyond the table
    edge, or further out if the board went so far that the plate is there, but never off the handle."""
    yaw = float(yaw_of(quat))
    axis = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    h = geo.parts[1]
    root, tip = h.pos[0] - h.half[0], h.pos[0] + h.half[0]
    s = (edge_x + GRASP_PAST_EDGE_M - pos[0]) / axis[0]
    s = min(max(s, root + 0.015), tip - 0.012)
    return pos + s * axis, yaw


def _costs(ctx: ContactContext):  # noqa: ANN202 - a bundle of closures
    cfg: PushPickBoardConfig = ctx.cfg  # type: ignore[assignment]
    geo = ctx.known.geometry["board"]
    edge = cfg.table.edge_x_m
    target = cfg.scoring.min_overhang_m + PUSH_MARGIN_M
    attract = Attractor(back_region(ctx), cfg.control.attractor_samples, seed=ctx.seed)

    def over(v: View) -> np.ndarray:
        return overhang(v.pos("board"), v.quat("board"), geo, edge)

    def push(v: View, y0: float, yaw0: float) -> np.ndarray:
        """Track a reference that leads the measured contact point at a steady speed, and stops where
        the measured overhang says the board is far enough: a shoved board would coast on."""
        b = v.obs.objects["board"]
        contact = attract.world_targets(b.pos, b.quat)[0]
        remaining = max(0.0, target - float(overhang(b.pos, b.quat, geo, edge)))
        tau = (np.arange(v.tcp.shape[1]) + 1) * v.batch.dt
        ref = np.broadcast_to(contact, (len(tau), 3)).copy()
        ref[:, 0] += np.minimum(PUSH_SPEED * tau + PUSH_LEAD_M, remaining + PUSH_LEAD_M * (remaining > 0))
        ov = over(v)
        board_yaw = yaw_of(v.quat("board"))
        return (20 * norm(v.tcp - ref[None]) + 100 * np.maximum(ov - target - 0.01, 0.0)
                + 40 * np.maximum(0.0, v.tcp[..., 2] - contact[2] - PUSH_Z) + pressing(v)
                + 5 * np.abs(v.pos("board")[..., 1] - y0) + 2 * np.abs(board_yaw - yaw0)
                + 0.5 * yaw_error(v.yaw, 0.0) ** 2 + W_SMOOTH * smoothness(v))

    return attract, over, push, target, edge


def push_pick_board_fsm(ctx: ContactContext) -> list[StageFactory]:
    cfg: PushPickBoardConfig = ctx.cfg  # type: ignore[assignment]
    attract, over, push, target, edge = _costs(ctx)
    geo = ctx.known.geometry["board"]
    opening = min(cfg.effector.max_opening_m, 2 * geo.parts[1].half[1] + 0.04)
    plan: dict[str, float] = {}

    def approach(obs: Observation) -> Stage:
        o = obs.objects["board"]
        behind = attract.world_targets(o.pos, o.quat)[0] - np.array([0.03, 0.0, 0.0])
        behind[2] = PUSH_Z
        return Stage("approach", hold_tcp(behind, 0.0, extra=lambda v: total(pressing(v))), lambda o2: near(o2, behind, 0.012), grip=0.0, timeout_s=4.0,
                     goal={"x_mm": behind[0] * 1000, "z_mm": PUSH_Z * 1000})

    def to_edge(obs: Observation) -> Stage:
        o = obs.objects["board"]
        y0, yaw0 = float(o.pos[1]), float(yaw_of(o.quat))

        def done(o2: Observation) -> bool:
            b = o2.objects["board"]
            # half the expert's margin: the servo lags a few newtons' worth behind the reference, so the board
            # settles a few millimetres short of the target
            return bool(overhang(b.pos, b.quat, geo, edge) >= target - PUSH_MARGIN_M / 2
                        and np.linalg.norm(b.lin_vel) < 0.01)

        return Stage("push", lambda v: total(push(v, y0, yaw0)), done, grip=0.0, hold_s=0.2, timeout_s=PUSH_TIMEOUT_S,
                     noise_scale=PUSH_NOISE,
                     attractors=(attract,), goal={"overhang_mm": target * 1000})

    def back_off(obs: Observation) -> Stage:
        up = obs.ee[:3] + np.array([-0.03, 0.0, 0.0])
        up[2] = TRAVEL_Z
        return Stage("back-off", hold_tcp(up, 0.0), lambda o: near(o, up, 0.015), grip=0.0, timeout_s=3.0,
                     seed_plan=_seed(up),
                     goal={"z_mm": up[2] * 1000})

    def reach(obs: Observation) -> Stage:
        b = obs.objects["board"]
        g, yaw = grasp_point(b.pos, b.quat, edge, geo)
        plan.update(yaw=yaw)
        above = np.array([g[0], g[1], TRAVEL_Z])
        return Stage("reach", _hold(above, yaw, floor=TRAVEL_Z - 0.02), lambda o: near(o, above, 0.01, yaw, 0.05), grip=opening,
                     timeout_s=4.0, seed_plan=_seed(above, yaw), goal={"x_mm": g[0] * 1000, "yaw_deg": math.degrees(yaw)})

    def descend(obs: Observation) -> Stage:
        b = obs.objects["board"]
        g, _ = grasp_point(b.pos, b.quat, edge, geo)
        down = np.array([g[0], g[1], GRASP_Z])

        def cost(v: View) -> np.ndarray:
            d = v.tcp - down
            run = 10 * norm(d) + 20 * norm(d[..., :2]) + YAW_W * yaw_error(v.yaw, plan["yaw"]) ** 2 + W_SMOOTH * smoothness(v)
            return total(run)

        return Stage("descend", cost, lambda o: near(o, down, 0.006), grip=opening, timeout_s=3.0,
                     seed_plan=_seed(down), noise_scale=DESCEND_NOISE,
                     goal={"z_mm": GRASP_Z * 1000})

    def grasp(obs: Observation) -> Stage:
        here = obs.ee[:3].copy()
        return Stage("grasp", _hold(here, plan["yaw"]), lambda o: bool(o.touch.min() > GRASP_TOUCH_N),
                     grip=0.0, hold_s=0.3, timeout_s=2.0, goal={"touch_n": GRASP_TOUCH_N})

    def lift(obs: Observation) -> Stage:
        up = np.array([obs.ee[0] - 0.03, obs.ee[1], LIFT_Z])
        return Stage("lift", _hold(up, plan["yaw"]), lambda o: near(o, up, 0.015) and o.touch.min() > 1.0,
                     grip=0.0, timeout_s=4.0, seed_plan=_seed(up), goal={"z_mm": LIFT_Z * 1000})

    def hold(obs: Observation) -> Stage:
        here = obs.ee[:3].copy()
        def still(o: Observation) -> bool:
            b = o.objects["board"]
            return bool(np.linalg.norm(b.lin_vel) < 0.015 and np.linalg.norm(b.ang_vel) < 0.2)

        # up to 8 s: a long board lifted by its handle can swing for several seconds (seed 9 still moved at 2.3 cm/s
        # after 4 s); the attempt's own budget still bounds it
        return Stage("hold", _hold(here, plan["yaw"]), still, hold_s=0.3, grip=0.0, noise_scale=0.25, timeout_s=8.0,
                     seed_plan=_seed(here, plan["yaw"]), goal={"hold_s": 0.3})

    return [approach, to_edge, back_off, reach, descend, grasp, lift, hold]


def push_pick_board_single(ctx: ContactContext) -> list[StageFactory]:
    """One cost: push while the predicted overhang is short; once it is pickable, go round the handle below
    the board, close when there, and lift once pinched."""
    cfg: PushPickBoardConfig = ctx.cfg  # type: ignore[assignment]
    attract, over, push, target, edge = _costs(ctx)
    geo = ctx.known.geometry["board"]
    opening = min(cfg.effector.max_opening_m, 2 * geo.parts[1].half[1] + 0.04)
    rest = geo.rest_z
    s_grasp = None

    def make(obs: Observation) -> Stage:
        nonlocal s_grasp
        o = obs.objects["board"]
        y0, yaw0 = float(o.pos[1]), float(yaw_of(o.quat))
        # where along the handle the pinch goes once the board has been pushed to the target overhang
        s_grasp = geo.parts[1].pos[0] + geo.parts[1].half[0] - target + GRASP_PAST_EDGE_M
        local = np.array([[s_grasp, 0.0, 0.0]])

        def cost(v: View) -> np.ndarray:
            ov = over(v)
            pickable = step_up(ov, cfg.scoring.min_overhang_m + 0.01, 0.008)
            g = v.to_world("board", local)[:, :, 0, :]
            xy = norm(v.tcp[..., :2] - g[..., :2])
            held = step_up(np.minimum(v.touch[..., 0], v.touch[..., 1]), 2.0, 1.5)
            lifted_z = v.pos("board")[..., 2] - rest
            height = np.where(xy > 0.012, 0.05, GRASP_Z)
            reach = 10 * xy + 10 * np.abs(v.tcp[..., 2] - height)
            close = step_up(-xy - np.abs(v.tcp[..., 2] - GRASP_Z), -0.012, 0.01)
            want_open = (1 - close) * (1 - held) * opening
            pick = ((1 - held) * reach + held * 20 * np.maximum(0.0, LIFT_Z - 0.03 - lifted_z)
                    + 200 * (v.ctrl[..., 4] - want_open) ** 2 + yaw_error(v.yaw, yaw_of(v.quat("board"))) ** 2)
            # while pushing, the fingertips stay behind the plate's back edge (never on top of the board)
            contact = v.to_world("board", attract.targets[:1])[:, :, 0, :]
            behind = 200 * np.maximum(v.tcp[..., 0] - contact[..., 0] - 0.006, 0.0)
            run = (1 - pickable) * (push(v, y0, yaw0) + behind + 200 * v.ctrl[..., 4] ** 2) + pickable * pick
            return total(run + W_SMOOTH * smoothness(v))

        def done(o2: Observation) -> bool:
            b = o2.objects["board"]
            return bool(b.pos[2] - rest > LIFT_Z - 0.1 and o2.touch.min() > 1.0)

        return Stage("push-pick", cost, done, timeout_s=cfg.control.episode_s, attractors=(attract,),
                     goal={"overhang_mm": target * 1000, "lift_mm": LIFT_Z * 1000})

    return [make, settle("hold", 1.5, grip=None)]
