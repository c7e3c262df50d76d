"""Expert costs for picking a box: T2 pick-box, and the pick half of T3 pick-clutter.

FSM: reach above the box with the hand turned across a side that fits -> descend around it
-> close until both pads feel it -> lift. Single stage: one cost that blends the same goals
by distance (open far away, closed near the grasp point, lift once held).
"""

from __future__ import annotations

import numpy as np

from kintsugi.tasks.contact.context import ContactContext
from kintsugi.tasks.contact.costs import View, norm, smoothness, step_up, total, yaw_error
from kintsugi.tasks.contact.experts.common import W_SMOOTH, grasp_yaw, hold_tcp, near, settle
from kintsugi.tasks.contact.fsm import Stage, StageFactory
from kintsugi.tasks.contact.robot import Observation

GRASP_TOUCH_N = 2.0
LIFT_M = 0.12
"""How high the expert lifts (the task asks for at least scoring.lift_m)."""
CLEAR_M = 0.025
DESCEND_NOISE = 0.35
"""MPPI's noise scale while the open fingers come down round the box."""


def grasp_height(ctx: ContactContext, obj: str) -> float:
    """Fingertip height that pinches a lying box around its middle, clear of the table."""
    h = ctx.known.geometry[obj].height
    return max(0.006, h / 2 - ctx.cfg.effector.finger_length_m / 3)


def pick_stages(ctx: ContactContext, obj: str) -> list[StageFactory]:
    geo = ctx.known.geometry[obj]
    top = geo.height
    opening = ctx.cfg.effector.max_opening_m
    z_grasp = grasp_height(ctx, obj)
    plan: dict[str, float] = {}

    def reach(obs: Observation) -> Stage:
        o = obs.objects[obj]
        others = [b.pos for k, b in obs.objects.items() if k != obj]
        yaw, width = grasp_yaw(geo, o.quat, float(obs.ee[3]), opening, o.pos, others)
        plan.update(yaw=yaw, open=min(opening, width + 0.035))

        def cost(v: View) -> np.ndarray:
            target = v.pos(obj).copy()
            target[..., 2] = top + CLEAR_M
            run = 10 * norm(v.tcp - target) + yaw_error(v.yaw, yaw) ** 2 + W_SMOOTH * smoothness(v)
            return total(run)

        def done(o2: Observation) -> bool:
            p = o2.objects[obj].pos
            return near(o2, np.array([p[0], p[1], top + CLEAR_M]), 0.012, yaw, 0.06)

        return Stage("reach", cost, done, grip=plan["open"], timeout_s=5.0, goal={"yaw_deg": float(np.degrees(yaw))})

    def descend(obs: Observation) -> Stage:
        yaw = plan["yaw"]

        def cost(v: View) -> np.ndarray:
            target = v.pos(obj).copy()
            target[..., 2] = z_grasp
            d = v.tcp - target
            run = 10 * norm(d) + 20 * norm(d[..., :2]) + yaw_error(v.yaw, yaw) ** 2 + W_SMOOTH * smoothness(v)
            return total(run)

        def done(o2: Observation) -> bool:
            p = o2.objects[obj].pos
            return near(o2, np.array([p[0], p[1], z_grasp]), 0.008)

        # fine sampling noise and a plan restarted at the grasp point: centimetre jitter here puts a finger
        # on the box's top edge and shoves it away
        p = obs.objects[obj].pos
        return Stage("descend", cost, done, grip=plan["open"], timeout_s=4.0, noise_scale=DESCEND_NOISE,
                     seed_plan={0: float(p[0]), 1: float(p[1]), 2: z_grasp}, goal={"z_mm": z_grasp * 1000})

    def grasp(obs: Observation) -> Stage:
        here = obs.ee[:3].copy()
        return Stage("grasp", hold_tcp(here, plan["yaw"]), lambda o: bool(o.touch.min() > GRASP_TOUCH_N),
                     grip=0.0, hold_s=0.2, timeout_s=2.0, goal={"touch_n": GRASP_TOUCH_N})

    def lift(obs: Observation) -> Stage:
        here = obs.ee[:3].copy()
        target = here + np.array([0.0, 0.0, LIFT_M])
        z0 = float(obs.objects[obj].pos[2])

        def extra(v: View) -> np.ndarray:
            return total(20 * np.maximum(0.0, z0 + LIFT_M - v.pos(obj)[..., 2]))

        def done(o2: Observation) -> bool:
            return bool(o2.objects[obj].pos[2] > z0 + LIFT_M - 0.02 and o2.touch.min() > 0.5)

        return Stage("lift", hold_tcp(target, plan["yaw"], extra=extra), done, grip=0.0, timeout_s=4.0,
                     goal={"lift_mm": LIFT_M * 1000})

    return [reach, descend, grasp, lift]


def pick_box_fsm(ctx: ContactContext) -> list[StageFactory]:
    return [*pick_stages(ctx, "box"), settle("hold", 0.5, grip=0.0)]


def pick_single(ctx: ContactContext, obj: str) -> StageFactory:
    """One cost for the whole pick: approach from above, open far / closed near, lift when held."""
    geo = ctx.known.geometry[obj]
    top = geo.height
    opening = ctx.cfg.effector.max_opening_m
    z_grasp = grasp_height(ctx, obj)

    def make(obs: Observation) -> Stage:
        o = obs.objects[obj]
        yaw, width = grasp_yaw(geo, o.quat, float(obs.ee[3]), opening)
        z0 = float(o.pos[2])

        def cost(v: View) -> np.ndarray:
            box = v.pos(obj)
            grasp_pt = box.copy()
            grasp_pt[..., 2] = box[..., 2] - z0 + z_grasp
            xy = norm(v.tcp[..., :2] - grasp_pt[..., :2])
            # stay above the box until aligned over it, then go down to the grasp height
            height = np.where(xy > 0.01, top + CLEAR_M, grasp_pt[..., 2])
            reach = 10 * xy + 10 * np.abs(v.tcp[..., 2] - height)
            close = step_up(-xy - np.abs(v.tcp[..., 2] - grasp_pt[..., 2]), -0.012, 0.01)
            want_open = (1 - close) * min(opening, width + 0.035)
            lift = 20 * np.maximum(0.0, z0 + LIFT_M - box[..., 2])
            run = (reach + lift + 200 * (v.ctrl[..., 4] - want_open) ** 2 + yaw_error(v.yaw, yaw) ** 2
                   + W_SMOOTH * smoothness(v))
            return total(run)

        def done(o2: Observation) -> bool:
            return bool(o2.objects[obj].pos[2] > z0 + LIFT_M - 0.02 and o2.touch.min() > 0.5)

        return Stage("pick", cost, done, timeout_s=ctx.cfg.control.episode_s, goal={"lift_mm": LIFT_M * 1000})

    return make


def pick_box_single(ctx: ContactContext) -> list[StageFactory]:
    return [pick_single(ctx, "box"), settle("hold", 0.5, grip=None)]
