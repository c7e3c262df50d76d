"""Expert costs for T3 pick-clutter: the pick stages (grasp side chosen clear of the distractors),
then carry above the goal -> lower until the box nearly touches -> open -> withdraw upward.

Single stage: one cost blending pick and place (carry the box to the goal once it is held,
open when it is low over the goal).
"""

from __future__ import annotations

import numpy as np

from kintsugi.tasks.contact.config import PickClutterConfig
from kintsugi.tasks.contact.context import ContactContext
from kintsugi.tasks.contact.costs import View, norm, smoothness, step_up, total
from kintsugi.tasks.contact.experts.common import W_SMOOTH, hold_tcp, near
from kintsugi.tasks.contact.experts.picking import LIFT_M, pick_single, pick_stages
from kintsugi.tasks.contact.fsm import Stage, StageFactory
from kintsugi.tasks.contact.robot import Observation

CARRY_Z = 0.14
"""Fingertip height while carrying: the box clears every distractor."""
SET_DOWN_M = 0.004
"""How far above the table the box's bottom is when the fingers open."""


def place_stages(ctx: ContactContext, obj: str) -> list[StageFactory]:
    cfg: PickClutterConfig = ctx.cfg  # type: ignore[assignment]
    goal = np.array(cfg.clutter.goal_m)
    hold: dict[str, float] = {}

    def carry(obs: Observation) -> Stage:
        b = obs.objects[obj]
        hold.update(dz=float(obs.ee[2] - b.pos[2]), yaw=float(obs.ee[3]),
                    dx=float(obs.ee[0] - b.pos[0]), dy=float(obs.ee[1] - b.pos[1]))
        above = np.array([goal[0] + hold["dx"], goal[1] + hold["dy"], CARRY_Z])

        def extra(v: View) -> np.ndarray:  # keep the box with the hand
            return total(20 * norm(v.pos(obj)[..., :2] - (v.tcp[..., :2] - [hold["dx"], hold["dy"]])))

        return Stage("carry", hold_tcp(above, hold["yaw"], extra=extra),
                     lambda o: near(o, above, 0.012) and float(np.linalg.norm(o.ee_vel[:3])) < 0.05,
                     grip=0.0, timeout_s=5.0, goal={"x_mm": goal[0] * 1000, "y_mm": goal[1] * 1000})

    def lower(obs: Observation) -> Stage:
        rest = ctx.known.geometry[obj].rest_z
        down = np.array([goal[0] + hold["dx"], goal[1] + hold["dy"], rest + SET_DOWN_M + hold["dz"]])
        return Stage("lower", hold_tcp(down, hold["yaw"]), lambda o: near(o, down, 0.006), grip=0.0, timeout_s=4.0,
                     goal={"z_mm": down[2] * 1000})

    def release(obs: Observation) -> Stage:
        here = obs.ee[:3].copy()
        opening = ctx.cfg.effector.max_opening_m
        return Stage("release", hold_tcp(here, hold["yaw"]), lambda o: o.opening > opening * 0.8 and o.touch.max() < 0.1,
                     grip=opening, timeout_s=2.0, goal={"open_mm": opening * 1000})

    def withdraw(obs: Observation) -> Stage:
        up = obs.ee[:3] + np.array([0.0, 0.0, 0.08])
        return Stage("withdraw", hold_tcp(up, hold["yaw"]), lambda o: near(o, up, 0.015),
                     grip=ctx.cfg.effector.max_opening_m, timeout_s=3.0, goal={"z_mm": up[2] * 1000})

    return [carry, lower, release, withdraw]


def pick_clutter_fsm(ctx: ContactContext) -> list[StageFactory]:
    return [*pick_stages(ctx, "box"), *place_stages(ctx, "box")]


def pick_clutter_single(ctx: ContactContext) -> list[StageFactory]:
    """One cost: the single-stage pick, with a carry-to-goal term and an open-when-set-down term once lifted."""
    cfg: PickClutterConfig = ctx.cfg  # type: ignore[assignment]
    goal = np.array(cfg.clutter.goal_m)
    pick = pick_single(ctx, "box")
    rest = ctx.known.geometry["box"].rest_z
    opening = cfg.effector.max_opening_m

    def make(obs: Observation) -> Stage:
        base = pick(obs)

        def cost(v: View) -> np.ndarray:
            box = v.pos("box")
            lifted = step_up(box[..., 2] - rest, 0.03, 0.02)
            to_goal = norm(box[..., :2] - goal)
            low_over_goal = step_up(-to_goal, -0.01, 0.008)
            place = 20 * to_goal + 10 * np.abs(box[..., 2] - (rest + SET_DOWN_M + (1 - low_over_goal) * LIFT_M))
            want_open = low_over_goal * opening
            run = lifted * (place + 200 * (v.ctrl[..., 4] - want_open) ** 2) + W_SMOOTH * smoothness(v)
            return base.cost(v) * (1 - float(obs.objects["box"].pos[2] > rest + 0.03)) + total(run)

        def done(o: Observation) -> bool:
            b = o.objects["box"]
            return bool(np.linalg.norm(b.pos[:2] - goal) < 0.02 and b.pos[2] < rest + 0.004 and o.touch.max() < 0.1)

        return Stage("pick-place", cost, done, timeout_s=cfg.control.episode_s, goal={"x_mm": goal[0] * 1000})

    return [make]
