"""Expert costs for T4 push-force: push the box to the wall with the closed fingers, then press 5 N.

FSM: approach behind the box, low -> push until the box touches the wall (tracker) ->
press with the target force (the F/T sensor; MPPI plans on the predicted force and Eq. 5
trims the command at the inner rate) until it has been held long enough. Single stage: one
cost that pushes the box to the wall and asks for the target force once it is there.
"""

from __future__ import annotations

import numpy as np

from kintsugi.control import ForceFeedbackConfig, force_feedback
from kintsugi.worlds.contact.config import PushForceConfig
from kintsugi.worlds.contact.context import ContactContext
from kintsugi.methods.mppi.costs import Attractor, ContactRegion, View, norm, smoothness, step_up, total, yaw_error
from kintsugi.methods.expert.designs.common import W_SMOOTH, near
from kintsugi.methods.mppi.fsm import Stage, StageFactory
from kintsugi.worlds.contact.push_force import wall_face_x
from kintsugi.worlds.contact.robot import Feedback, Observation
from kintsugi.worlds.contact.spec import corners
from kintsugi.worlds.contact.world import rotate, yaw_of

PUSH_Z = 0.008
"""Fingertip height while pushing: low on the box's side, so it slides rather than tips."""
PADDLE = 0.01
"""Half the closed fingers' extent along x: the TCP sits this far behind the face it pushes."""
FB_GAIN = 0.6
"""Eq. 5 gain as a fraction of the servo's compliance (1 / kp): metres of command per newton of error."""


def back_region(ctx: ContactContext) -> ContactRegion:
    """The box's -x face, low: where the closed fingers push."""
    geo = ctx.known.geometry["box"]
    hx, _, hz = geo.parts[0].half
    return ContactRegion(obj="box", center=(-hx, 0.0, -hz + PUSH_Z + 0.006), normal=(-1.0, 0.0, 0.0), radius=0.008,
                         standoff=PADDLE, drop=0.006)


def front_x(view_or_pos: np.ndarray, quat: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """x of the box's most forward corner for poses (..., 3), (..., 4)."""
    q = np.broadcast_to(quat[..., None, :], (*quat.shape[:-1], len(pts), 4))
    return (view_or_pos[..., None, :] + rotate(q, np.broadcast_to(pts, (*quat.shape[:-1], *pts.shape))))[..., 0].max(-1)


def _feedback(cfg: PushForceConfig) -> Feedback:
    k = FB_GAIN / cfg.effector.kp_n_per_m
    fb = ForceFeedbackConfig(gain=((k,), (0.0,), (0.0,), (0.0,), (0.0,)), max_correction=0.01)

    def apply(obs: Observation, planned: np.ndarray) -> np.ndarray:
        return force_feedback(planned, obs.force[:1], np.array([cfg.force.target_n]), fb)

    return apply


def _costs(ctx: ContactContext):  # noqa: ANN202 - a bundle of closures
    cfg: PushForceConfig = ctx.cfg  # type: ignore[assignment]
    pts = corners(ctx.known.geometry["box"])
    face = wall_face_x(cfg.wall)
    target = cfg.force.target_n
    attract = Attractor(back_region(ctx), cfg.control.attractor_samples, seed=ctx.seed)

    def gap(v: View) -> np.ndarray:
        return face - front_x(v.pos("box"), v.quat("box"), pts)

    def push(v: View, y0: float) -> np.ndarray:
        speed = np.abs(v.vel("box")[..., 0])
        return (30 * np.maximum(gap(v), 0.0) + 10 * attract.distance(v) + 5 * np.abs(v.pos("box")[..., 1] - y0)
                + 20 * np.maximum(speed - 0.08, 0.0) + 0.5 * yaw_error(v.yaw, 0.0) ** 2 + W_SMOOTH * smoothness(v))

    def press(v: View) -> np.ndarray:
        # L1 in units of the tolerance: a wrong force costs in proportion, so letting go is never a bargain
        f_err = np.abs(v.force[..., 0] - target) / cfg.force.tolerance_n
        return 3 * f_err + 300 * attract.distance(v) + 100 * np.maximum(gap(v), 0.0) + W_SMOOTH * smoothness(v)

    return attract, gap, push, press, pts, face


def push_force_fsm(ctx: ContactContext) -> list[StageFactory]:
    cfg: PushForceConfig = ctx.cfg  # type: ignore[assignment]
    attract, gap, push, press, pts, face = _costs(ctx)

    def approach(obs: Observation) -> Stage:
        o = obs.objects["box"]
        behind = attract.world_targets(o.pos, o.quat)[0] - np.array([0.03, 0.0, 0.0])
        behind[2] = PUSH_Z

        def cost(v: View) -> np.ndarray:
            run = 10 * norm(v.tcp - behind) + 0.5 * yaw_error(v.yaw, 0.0) ** 2 + W_SMOOTH * smoothness(v)
            return total(run)

        return Stage("approach", cost, lambda o2: near(o2, behind, 0.012), grip=0.0, timeout_s=4.0,
                     goal={"x_mm": behind[0] * 1000, "z_mm": PUSH_Z * 1000})

    def to_wall(obs: Observation) -> Stage:
        y0 = float(obs.objects["box"].pos[1])

        def done(o2: Observation) -> bool:
            b = o2.objects["box"]
            return bool(face - front_x(b.pos, b.quat, pts) < 0.002 and np.linalg.norm(b.lin_vel) < 0.02)

        return Stage("push", lambda v: total(push(v, y0)), done, grip=0.0, hold_s=0.3, timeout_s=5.0,
                     attractors=(attract,),
                     goal={"wall_x_mm": face * 1000})

    def hold(obs: Observation) -> Stage:
        tol = 0.4 * cfg.force.tolerance_n

        def done(o2: Observation) -> bool:  # the right force, on a box that is against the wall
            b = o2.objects["box"]
            return bool(abs(o2.force[0] - cfg.force.target_n) < tol and face - front_x(b.pos, b.quat, pts) < 0.002)

        return Stage("press", lambda v: total(press(v)), done,
                     grip=0.0, hold_s=cfg.force.duration_s + 0.5, timeout_s=cfg.force.duration_s + 4.0,
                     feedback=_feedback(cfg), attractors=(attract,), noise_scale=0.15,
                     seed_plan={0: float(obs.ee[0]) + cfg.force.target_n / cfg.effector.kp_n_per_m},
                     goal={"force_n": cfg.force.target_n, "hold_s": cfg.force.duration_s + 0.5})

    return [approach, to_wall, hold]


SINGLE_NOISE = 0.3
"""MPPI's noise scale for the whole single-stage push: one stage has one scale, a compromise between
reaching behind the box (centimetres) and holding 5 N on a 600 N/m servo (the FSM's press uses 0.15)."""
CLEAR_M = 0.02
"""The single cost keeps the fingertips this far above the box's top anywhere ahead of its back face."""
ENGAGED_M = 0.01
"""The single cost counts a push only with the TCP this close to the back-face patch (blended over a few mm)."""
PUSHING_N = 2.5
"""Measured push force around which the single stage's Eq. 5 term fades in (a free hand reads < 1 N)."""


def _pushing_feedback(cfg: PushForceConfig) -> Feedback:
    """Eq. 5 on the measured push force, its gain faded in smoothly with that force: the term trims a push
    that is on, and stays out of a free hand's way (one stage runs throughout; the FSM only runs it while
    it presses)."""
    base = _feedback(cfg)

    def apply(obs: Observation, planned: np.ndarray) -> np.ndarray:
        w = float(step_up(np.array(obs.force[0]), PUSHING_N, 1.5))
        return planned + w * (base(obs, planned) - planned)

    return apply


FACE_HALF_Y_M = 0.01
FACE_Z_M = (0.004, 0.016)
"""Where on the back face the single cost lets the closed fingers push: within FACE_HALF_Y_M of its middle,
the TCP this high (a point target pulled the fingers down along the face while they pressed on it: pad
friction held them, and the planner paid for the slide with a weaker push)."""


Z_WEIGHT = 2.5
"""How much a height error counts against an xy one in `to_face`: z's sampling noise is 2.5x smaller than x's,
so an unweighted z came down slowly."""


def _box_frame(v: View) -> tuple[np.ndarray, np.ndarray]:
    """The TCP's (x, y) offset from the box centre, in the box's yaw frame, each (K, T)."""
    yaw = yaw_of(v.quat("box"))
    d = v.tcp[..., :2] - v.pos("box")[..., :2]
    return d[..., 0] * np.cos(yaw) + d[..., 1] * np.sin(yaw), -d[..., 0] * np.sin(yaw) + d[..., 1] * np.cos(yaw)


def to_face(ctx: ContactContext, v: View) -> np.ndarray:
    """(K, T) distance from the TCP to where the closed fingers push the box's back face (a patch, not a point)."""
    hx = ctx.known.geometry["box"].parts[0].half[0]
    local_x, local_y = _box_frame(v)
    z = v.tcp[..., 2]
    off = np.stack([local_x - (-hx - PADDLE), np.maximum(0.0, np.abs(local_y) - FACE_HALF_Y_M),
                    Z_WEIGHT * (np.maximum(0.0, FACE_Z_M[0] - z) + np.maximum(0.0, z - FACE_Z_M[1]))], axis=-1)
    return norm(off)


def ahead_of_back(ctx: ContactContext, v: View) -> np.ndarray:
    """Smooth 0 -> 1 as the TCP moves ahead (box frame +x) of where the closed fingers touch the back face
    (from about 5 mm on: a finger that far ahead would come down on the box's top edge)."""
    hx = ctx.known.geometry["box"].parts[0].half[0]
    local_x, _ = _box_frame(v)
    return step_up(local_x - (-hx - PADDLE), 0.008, 0.003)


def push_force_single(ctx: ContactContext) -> list[StageFactory]:
    """One cost for the whole task: push with the target force, at the back face, toward the wall.

    The force term is never switched off: every sample pays for its push's distance from the target (no push
    where the hand is not at the back face), so pushing the box at all is better than not. The former single
    cost switched a force term on as the predicted box reached the wall: arriving there with the sliding
    force (~2 N) cost more than stopping 1-2 cm short, where the box stayed. Coming straight at the attractor
    the hand landed on the box's top edge: it is kept above the box's top anywhere ahead of the back face.
    (The FSM's contact region is only drawn in videos; the cost uses the patch of `to_face`.)"""
    cfg: PushForceConfig = ctx.cfg  # type: ignore[assignment]
    attract, gap, _, _, pts, face = _costs(ctx)
    top = ctx.known.geometry["box"].height
    target, tol = cfg.force.target_n, cfg.force.tolerance_n
    kp = cfg.effector.kp_n_per_m

    def make(obs: Observation) -> Stage:
        y0 = float(obs.objects["box"].pos[1])

        def cost(v: View) -> np.ndarray:
            att = to_face(ctx, v)
            # the push force of a position servo at rest is its stiffness times how far the command leads the
            # hand: asking for that lead is exact where the predicted wrist force is noisy (it also feels the
            # hand's own accelerations: jerking a free hand read 3-4 N); away from the back face no push counts
            at_face = step_up(-att, -ENGAGED_M, 0.006)
            hand_x = v.batch.qpos[:, :, v.layout.ee_qpos[0]]  # the servo's own coordinate (the TCP is offset)
            push_n = kp * (v.ctrl[..., 0] - hand_x)
            f_err = (at_face * np.abs(push_n - target) + (1 - at_face) * target) / tol
            # a little against pushing sideways (the fingers slid along the face, the x force dipping); more, and
            # every sample's sideways noise outweighed what its x command did (at 3 per N no sample beat the plan)
            side_n = at_face * kp * np.abs(v.ctrl[..., 1] - v.batch.qpos[:, :, v.layout.ee_qpos[1]])
            over = np.maximum(0.0, top + CLEAR_M - v.tcp[..., 2]) * ahead_of_back(ctx, v)
            speed = np.abs(v.vel("box")[..., 0])
            # the force now counts most: it is what the next command does (later knots are replanned anyway)
            soon = np.linspace(2.0, 0.5, f_err.shape[1])
            run = (3 * soon * f_err + 0.2 * side_n + 300 * att + 30 * np.maximum(gap(v), 0.0) + 300 * over
                   + 5 * np.abs(v.pos("box")[..., 1] - y0) + 20 * np.maximum(speed - 0.08, 0.0)
                   + 10 * np.abs(yaw_error(v.yaw, 0.0)) + W_SMOOTH * smoothness(v))
            return total(run)

        def done(o: Observation) -> bool:  # the right force, on a box that is against the wall
            b = o.objects["box"]
            return bool(abs(o.force[0] - target) < 0.6 * tol and face - front_x(b.pos, b.quat, pts) < 0.002)

        return Stage("push-press", cost, done, grip=0.0, hold_s=cfg.force.duration_s + 0.5,
                     timeout_s=cfg.control.episode_s, noise_scale=SINGLE_NOISE, attractors=(attract,),
                     feedback=_pushing_feedback(cfg),
                     goal={"force_n": target})

    return [make]
