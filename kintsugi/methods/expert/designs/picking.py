"""Expert costs for picking a box: T2 pick-box, and the pick half of T3 pick-clutter.

FSM: reach above the box with the hand turned across a side that fits -> descend around it
-> close until both pads feel it -> lift. Single stage: one cost that blends the same goals
by distance (open far away, closed near the grasp point, lift once held).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kintsugi.worlds.contact.context import ContactContext
from kintsugi.methods.mppi.costs import View, norm, smoothness, step_up, total, yaw_error
from kintsugi.methods.expert.designs.common import W_SMOOTH, grasp_yaw, hold_tcp, near, settle
from kintsugi.methods.mppi.fsm import Stage, StageFactory
from kintsugi.worlds.contact.robot import Observation

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


SINGLE_NOISE = 0.5
"""MPPI's noise scale for the whole single-stage pick: one stage has one scale, so it is a compromise
between reaching (centimetres) and coming down round the box (the FSM's descend uses DESCEND_NOISE)."""
FUNNEL_IN_M = 0.008
FUNNEL_OUT_M = 0.022
"""The single cost lets the open fingers down to the grasp height within FUNNEL_IN_M of the grasp point
across the pinch (open OPEN_MARGIN_M wider than the box, they clear it by about 12 mm) and keeps them above
its top beyond FUNNEL_OUT_M, blended smoothly in between. Along the fingers an offset counts half."""
SQUEEZE_M = 0.008
"""The single cost closes the gripper command this far inside the box's width (12 N of squeeze) rather than
to 0: MPPI moves a sampled command a few millimetres per step, so every millimetre of travel costs time."""
CLOSE_FROM = 0.6
"""The single cost's gripper target closes linearly from this fraction of the way between the box's top and
the grasp height down to the grasp height (the pads meet the box a few millimetres above it)."""
OPEN_MARGIN_M = 0.025
"""The single cost opens this much wider than the box (the FSM opens 35 mm wider; less travel to close)."""
HELD_N = 1.0
"""Predicted force on each pad at which the single cost counts the box as pinched."""


def funnel(offset: np.ndarray, yaw: float) -> np.ndarray:
    """Smooth 1 -> 0 as the hand's xy offset (..., 2) from the grasp point grows from FUNNEL_IN_M to FUNNEL_OUT_M.

    A hard switch on the offset put most sampled descents on its wrong side (the hand hovered over the box);
    the fingers only hit the box when off across the pinch, so an offset along them counts half."""
    across = -offset[..., 0] * np.sin(yaw) + offset[..., 1] * np.cos(yaw)
    along = offset[..., 0] * np.cos(yaw) + offset[..., 1] * np.sin(yaw)
    d = np.sqrt(across ** 2 + (along / 2) ** 2)
    mid, half = (FUNNEL_IN_M + FUNNEL_OUT_M) / 2, (FUNNEL_OUT_M - FUNNEL_IN_M) / 2
    return 1.0 - step_up(d, mid, half)


@dataclass(frozen=True)
class GraspTerms:
    """The single-stage pick's hand terms for one box, fixed when the stage starts (side to pinch, widths)."""

    obj: str
    yaw: float
    open_w: float
    squeeze: float
    z0: float
    top: float
    z_grasp: float

    def __call__(self, v: View) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(reach cost, gripper command wanted, held in [0, 1]), each (K, T), on the predicted state."""
        box = v.pos(self.obj)
        grasp_pt = box.copy()
        grasp_pt[..., 2] = box[..., 2] - self.z0 + self.z_grasp
        offset = v.tcp[..., :2] - grasp_pt[..., :2]
        dz = v.tcp[..., 2] - grasp_pt[..., 2]
        over = funnel(offset, self.yaw)
        # always drawn down to the grasp height, but kept above a cone round the box (open fingers clear it)
        cone = (1 - over) * (self.top + CLEAR_M - self.z_grasp)
        # weights in proportion to the sampling noise per axis (z's is 2.5x smaller than x's), so MPPI's
        # selection presses on every axis, not on xy alone (with 30 xy / 10 z the hand came down at 2 cm/s)
        reach = 15 * norm(offset) + 30 * np.abs(dz) + 60 * np.maximum(0.0, cone - dz)
        # close gradually on the way down round the box (MPPI moves a sampled command a few mm per step,
        # so a close that waits for the grasp height would hold the hand up: open costs more the lower it
        # gets), and keep squeezing whatever the pads hold (a sag must not open them)
        down = over * np.clip(1 - dz / (CLOSE_FROM * (self.top - self.z_grasp)), 0.0, 1.0)
        held = step_up(v.touch.min(axis=-1), HELD_N, 0.8)
        closing = np.maximum(down, held)
        return reach, closing * self.squeeze + (1 - closing) * self.open_w, held


def grasp_terms(ctx: ContactContext, obj: str, obs: Observation, squeeze_m: float = SQUEEZE_M) -> GraspTerms:
    """The grasp side (clear of other objects, as the FSM chooses it) and the widths for the box as seen now;
    `squeeze_m`: how far inside the box's width the gripper command closes."""
    geo = ctx.known.geometry[obj]
    opening = ctx.cfg.effector.max_opening_m
    o = obs.objects[obj]
    others = [b.pos for k, b in obs.objects.items() if k != obj]
    yaw, width = grasp_yaw(geo, o.quat, float(obs.ee[3]), opening, o.pos, others)
    return GraspTerms(obj=obj, yaw=yaw, open_w=min(opening, width + OPEN_MARGIN_M),
                      squeeze=max(0.0, width - squeeze_m), z0=float(o.pos[2]), top=geo.height,
                      z_grasp=grasp_height(ctx, obj))


def pick_single(ctx: ContactContext, obj: str) -> StageFactory:
    """One cost for the whole pick: funnel down round the box, open far / closed at the grasp point,
    lift once the (predicted) pads hold it. Done when it has been held lifted for a moment."""

    def make(obs: Observation) -> Stage:
        hand = grasp_terms(ctx, obj, obs)
        z0 = hand.z0

        def cost(v: View) -> np.ndarray:
            reach, want_open, _ = hand(v)
            grip = 15 * np.abs(v.ctrl[..., 4] - want_open)
            lift = 30 * np.maximum(0.0, z0 + LIFT_M - v.pos(obj)[..., 2])
            run = reach + grip + lift + yaw_error(v.yaw, hand.yaw) ** 2 + W_SMOOTH * smoothness(v)
            return total(run)

        def done(o2: Observation) -> bool:
            return bool(o2.objects[obj].pos[2] > z0 + LIFT_M - 0.02 and o2.touch.min() > 0.5)

        return Stage("pick", cost, done, hold_s=0.5, timeout_s=ctx.cfg.control.episode_s, noise_scale=SINGLE_NOISE,
                     goal={"lift_mm": LIFT_M * 1000})

    return make


def pick_box_single(ctx: ContactContext) -> list[StageFactory]:
    return [pick_single(ctx, "box")]
