"""Expert costs for T5 flip-box: push high on the tall box's back face with the closed fingers until it
is past tipping, then draw the hand back and let it settle on its side.

Single stage: one cost asking for a lying box, with the back-face attractor while it still stands
and the hand kept clear once it is down.
"""

from __future__ import annotations

import numpy as np

from kintsugi.worlds.contact.config import FlipBoxConfig
from kintsugi.worlds.contact.context import ContactContext
from kintsugi.methods.mppi.costs import Attractor, ContactRegion, View, norm, smoothness, step_up, total, yaw_error
from kintsugi.methods.expert.designs.common import W_SMOOTH, hold_tcp, near, settle
from kintsugi.methods.mppi.fsm import Stage, StageFactory
from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.world import tilt_deg

PUSH_HEIGHT = 0.7
"""Where the fingertips meet the back face, as a fraction of the box's height (high: it tips, not slides)."""
PADDLE = 0.01
TIPPED_DEG = 45.0
PIVOT_DONE_DEG = 125.0
REACH_OVER_M = 0.06
"""flip-wall: how far past the curb's face the pushing hand may go (far enough to carry the box off the
curb top, where a box flipped in place would balance)."""
"""flip-wall: the hand lets go only this far past upright; a box let go near 100 deg can rock back."""


def top_region(ctx: ContactContext) -> ContactRegion:
    hx, _, hz = ctx.known.geometry["box"].parts[0].half
    return ContactRegion(obj="box", center=(-hx, 0.0, -hz + PUSH_HEIGHT * 2 * hz), normal=(-1.0, 0.0, 0.0),
                         radius=0.01, standoff=PADDLE)


def flip_box_fsm(ctx: ContactContext) -> list[StageFactory]:
    cfg: FlipBoxConfig = ctx.cfg  # type: ignore[assignment]
    attract = Attractor(top_region(ctx), cfg.control.attractor_samples, seed=ctx.seed)

    def approach(obs: Observation) -> Stage:
        o = obs.objects["box"]
        behind = attract.world_targets(o.pos, o.quat)[0] - np.array([0.04, 0.0, 0.0])
        return Stage("approach", hold_tcp(behind, 0.0), lambda o2: near(o2, behind, 0.012), grip=0.0, timeout_s=4.0,
                     goal={"z_mm": behind[2] * 1000})

    def tip(obs: Observation) -> Stage:
        def cost(v: View) -> np.ndarray:
            up_z = v.up("box")[..., 2]
            run = (5 * up_z + 10 * attract.distance(v) * step_up(up_z, 0.75, 0.1) + 0.5 * yaw_error(v.yaw, 0.0) ** 2
                   + W_SMOOTH * smoothness(v))
            return total(run)

        return Stage("tip", cost, lambda o: float(tilt_deg(o.objects["box"].quat)) > TIPPED_DEG, grip=0.0,
                     timeout_s=5.0, attractors=(attract,), goal={"tilt_deg": TIPPED_DEG})

    def withdraw(obs: Observation) -> Stage:
        back = obs.ee[:3] + np.array([-0.06, 0.0, 0.06])

        def done(o: Observation) -> bool:
            b = o.objects["box"]
            return bool(near(o, back, 0.015) and float(tilt_deg(b.quat)) > cfg.scoring.flip_deg
                        and np.linalg.norm(b.lin_vel) < 0.01 and np.linalg.norm(b.ang_vel) < 0.2)

        return Stage("withdraw", hold_tcp(back, 0.0), done, grip=0.0, timeout_s=3.0, goal={"x_mm": back[0] * 1000})

    return [approach, tip, withdraw, settle("settle", 0.3, grip=0.0)]


def flip_box_single(ctx: ContactContext) -> list[StageFactory]:
    cfg: FlipBoxConfig = ctx.cfg  # type: ignore[assignment]
    attract = Attractor(top_region(ctx), cfg.control.attractor_samples, seed=ctx.seed)

    def make(obs: Observation) -> Stage:
        def cost(v: View) -> np.ndarray:
            up_z = v.up("box")[..., 2]
            standing = step_up(up_z, 0.75, 0.1)
            away = norm(v.tcp[..., :2] - v.pos("box")[..., :2])
            run = (5 * up_z + 10 * attract.distance(v) * standing + 2 * (1 - standing) * np.maximum(0.0, 0.12 - away)
                   + 0.5 * yaw_error(v.yaw, 0.0) ** 2 + W_SMOOTH * smoothness(v))
            return total(run)

        def done(o: Observation) -> bool:
            b = o.objects["box"]
            return bool(float(tilt_deg(b.quat)) > cfg.scoring.flip_deg and np.linalg.norm(b.lin_vel) < 0.01
                        and np.linalg.norm(b.ang_vel) < 0.2 and o.touch.max() < 0.05)

        return Stage("flip", cost, done, grip=0.0, hold_s=0.3, timeout_s=cfg.control.episode_s,
                     attractors=(attract,), goal={"tilt_deg": cfg.scoring.flip_deg})

    return [make]


def flip_wall_fsm(ctx: ContactContext) -> list[StageFactory]:
    """Approach low -> push the box against the curb -> push high on its back until it stands -> withdraw."""
    from kintsugi.methods.expert.designs.pushing import PUSH_Z, back_region, front_x
    from kintsugi.worlds.contact.push_force import wall_face_x
    from kintsugi.worlds.contact.spec import corners

    cfg = ctx.cfg
    face = wall_face_x(cfg.wall)  # type: ignore[attr-defined]
    pts = corners(ctx.known.geometry["box"])
    low = Attractor(back_region(ctx), cfg.control.attractor_samples, seed=ctx.seed)
    high = Attractor(top_region(ctx), cfg.control.attractor_samples, seed=ctx.seed)

    def approach(obs: Observation) -> Stage:
        o = obs.objects["box"]
        behind = low.world_targets(o.pos, o.quat)[0] - np.array([0.03, 0.0, 0.0])
        behind[2] = PUSH_Z
        return Stage("approach", hold_tcp(behind, 0.0), lambda o2: near(o2, behind, 0.012), grip=0.0, timeout_s=4.0,
                     goal={"x_mm": behind[0] * 1000})

    def to_curb(obs: Observation) -> Stage:
        y0 = float(obs.objects["box"].pos[1])

        def cost(v: View) -> np.ndarray:
            gap = face - front_x(v.pos("box"), v.quat("box"), pts)
            speed = np.abs(v.vel("box")[..., 0])
            return total(30 * np.maximum(gap, 0.0) + 10 * low.distance(v) + 5 * np.abs(v.pos("box")[..., 1] - y0)
                         + 20 * np.maximum(speed - 0.08, 0.0) + 0.5 * yaw_error(v.yaw, 0.0) ** 2
                         + W_SMOOTH * smoothness(v))

        def done(o: Observation) -> bool:
            b = o.objects["box"]
            return bool(face - front_x(b.pos, b.quat, pts) < 0.003 and np.linalg.norm(b.lin_vel) < 0.02)

        return Stage("push", cost, done, grip=0.0, hold_s=0.2, timeout_s=5.0, attractors=(low,),
                     goal={"curb_x_mm": face * 1000})

    def rise(obs: Observation) -> Stage:
        o = obs.objects["box"]
        above = high.world_targets(o.pos, o.quat)[0] - np.array([0.035, 0.0, 0.0])  # clear of the face: no drag
        return Stage("rise", hold_tcp(above, 0.0), lambda o2: near(o2, above, 0.015), grip=0.0, timeout_s=4.0,
                     goal={"z_mm": above[2] * 1000})

    def pivot(obs: Observation) -> Stage:
        def cost(v: View) -> np.ndarray:
            up_z = v.up("box")[..., 2]
            # the hand never needs to pass the curb, and a box flung over it ends off the table
            reach_over = np.maximum(v.tcp[..., 0] - face - REACH_OVER_M, 0.0)
            fling = np.maximum(norm(v.vel("box")) - 0.3, 0.0)
            return total(5 * up_z + 10 * high.distance(v) * step_up(up_z, 0.5, 0.2) + 0.5 * yaw_error(v.yaw, 0.0) ** 2
                         + 100 * reach_over + 20 * fling + W_SMOOTH * smoothness(v))

        # past upright, so it settles over the curb instead of falling back
        return Stage("pivot", cost, lambda o: float(tilt_deg(o.objects["box"].quat)) > PIVOT_DONE_DEG, grip=0.0,
                     timeout_s=6.0, attractors=(high,), goal={"tilt_deg": PIVOT_DONE_DEG})

    def lift_off(obs: Observation) -> Stage:
        # straight up first: fingertips resting on the stood-up box would drag it back over the curb
        up = obs.ee[:3] + np.array([0.0, 0.0, 0.05])
        return Stage("lift-off", hold_tcp(up, 0.0), lambda o: near(o, up, 0.012), grip=0.0, timeout_s=2.0,
                     noise_scale=0.4, seed_plan={2: float(up[2])}, goal={"z_mm": up[2] * 1000})

    def withdraw(obs: Observation) -> Stage:
        back = obs.ee[:3] + np.array([-0.06, 0.0, 0.0])

        def done(o: Observation) -> bool:
            b = o.objects["box"]
            return bool(near(o, back, 0.015) and float(tilt_deg(b.quat)) > cfg.scoring.flip_deg  # type: ignore[attr-defined]
                        and np.linalg.norm(b.lin_vel) < 0.01 and np.linalg.norm(b.ang_vel) < 0.2)

        return Stage("withdraw", hold_tcp(back, 0.0), done, grip=0.0, timeout_s=3.0, goal={"x_mm": back[0] * 1000})

    return [approach, to_curb, rise, pivot, lift_off, withdraw, settle("settle", 1.0, grip=0.0)]


def flip_wall_single(ctx: ContactContext) -> list[StageFactory]:
    """The flip-box single-stage cost as is (stand the box up, attractor high on its back): no curb logic."""
    return flip_box_single(ctx)
