"""Expert costs for T4 push-force: push the box to the wall with the closed fingers, then press 5 N.

FSM: approach behind the box, low -> push until the box touches the wall (tracker) ->
press with the target force (the F/T sensor; MPPI plans on the predicted force and Eq. 5
trims the command at the inner rate) until it has been held long enough. Single stage: one
cost that pushes the box to the wall and asks for the target force once it is there.
"""

from __future__ import annotations

import numpy as np

from kintsugi.control import ForceFeedbackConfig, force_feedback
from kintsugi.tasks.contact.config import PushForceConfig
from kintsugi.tasks.contact.context import ContactContext
from kintsugi.tasks.contact.costs import Attractor, ContactRegion, View, norm, smoothness, step_up, total, yaw_error
from kintsugi.tasks.contact.experts.common import W_SMOOTH, near
from kintsugi.tasks.contact.fsm import Stage, StageFactory
from kintsugi.tasks.contact.push_force import wall_face_x
from kintsugi.tasks.contact.robot import Feedback, Observation
from kintsugi.tasks.contact.spec import corners
from kintsugi.tasks.contact.world import rotate

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


def push_force_single(ctx: ContactContext) -> list[StageFactory]:
    """One cost: push the box to the wall; the force term switches on (smoothly) as the gap closes."""
    cfg: PushForceConfig = ctx.cfg  # type: ignore[assignment]
    attract, gap, push, press, _, _ = _costs(ctx)

    def make(obs: Observation) -> Stage:
        y0 = float(obs.objects["box"].pos[1])

        def cost(v: View) -> np.ndarray:
            at_wall = step_up(-gap(v), -0.004, 0.003)
            return total((1 - at_wall) * push(v, y0) + at_wall * press(v))

        tol = 0.6 * cfg.force.tolerance_n
        return Stage("push-press", cost, lambda o: abs(o.force[0] - cfg.force.target_n) < tol, grip=0.0,
                     hold_s=cfg.force.duration_s + 0.5, timeout_s=cfg.control.episode_s,
                     attractors=(attract,), goal={"force_n": cfg.force.target_n})

    return [make]
