"""Object poses from the robot's own camera: segmentation + depth renders, fitted with each object's known model.

Every `1 / rate_hz` seconds of sim time the scene camera (`camera.*`) renders a segmentation and a depth image
of the evaluation world (real offscreen rendering, MUJOCO_GL=egl). Each depth pixel gets the noise of a
structured-light camera (`depth_noise_m` at 1 m, growing with the square of the distance); an object's pixels
(its segment) become a point cloud in the world, and the object's known model (its parts: boxes, cylinders,
spheres) is moved onto it by a robust rigid fit (`kintsugi.perception.rigid_fit`), starting from the last
estimate carried on by its velocity. A frame's poses reach the robot `latency_s` after the frame was taken;
velocities are the difference of the last two estimates. Before its first estimate the robot waits for
the camera (the scene is at rest before the robot moves). An object with fewer than `min_points` pixels in
view (hidden behind the hand) keeps its last pose, and one never seen is a `PerceptionError`.

This is what `perception.poses = "perceived"` gives a method; `"truth"` is the exact tracker (an oracle).
The estimator reads the simulator only through the renders: never an object's pose, mass or friction.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import mujoco
import numpy as np

from kintsugi.core.errors import KintsugiError
from kintsugi.perception.cloud import object_clouds
from kintsugi.perception.render import SegDepthRenderer
from kintsugi.perception.rigid_fit import FitSettings, fit_quality, rigid_fit
from kintsugi.perception.sdf import box_sdf, cylinder_sdf, sphere_sdf
from kintsugi.worlds.contact.objects import AXES, Geometry, Part

I3 = np.eye(3)
MAX_POINTS = 400
"""Points per object and frame the fit uses (evenly thinned): enough for a sub-millimetre pose."""
STARTS_DEG = (0.0, 45.0, 90.0, 135.0)
"""Headings the first fit of an object starts from (upright); the best fit wins."""


class PerceptionError(KintsugiError):
    """An object the robot must track was never seen by its camera."""


@dataclass(frozen=True)
class Estimate:
    t: float
    pos: np.ndarray
    rot: np.ndarray  # (3, 3) object frame in the world
    rms_m: float
    points: int


def _part_sdf(part: Part):  # noqa: ANN202
    he = np.asarray(part.half, float)
    centre = np.asarray(part.pos, float)
    if part.shape == "box":
        return lambda x: box_sdf(x - centre, he)
    if part.shape == "sphere":
        return lambda x: sphere_sdf(x - centre, float(he[0]))
    axis = AXES[part.axis]  # cylinder (a capsule is fitted as the cylinder of its bounding size)
    order = [i for i in range(3) if i != axis] + [axis]
    back = np.argsort(order)

    def sdf(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d, g = cylinder_sdf((x - centre)[:, order], part.radius, float(he[axis]))
        return d, g[:, back]

    return sdf


def model_sdf(geo: Geometry):  # noqa: ANN201
    """Signed distance (and gradient) to the union of an object's parts, in its own frame."""
    parts = [_part_sdf(p) for p in geo.parts]
    if len(parts) == 1:
        return parts[0]

    def sdf(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ds, gs = zip(*(f(x) for f in parts))
        d, g = np.stack(ds), np.stack(gs)
        i = d.argmin(axis=0)
        rows = np.arange(len(x))
        return d[i, rows], g[i, rows]

    return sdf


def _turn(axis: int, deg: float) -> np.ndarray:
    c, s = round(math.cos(math.radians(deg))), round(math.sin(math.radians(deg)))
    i, j = [k for k in range(3) if k != axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def _symmetries(geo: Geometry) -> tuple[list[np.ndarray], int | None]:
    """Turns of the model's own frame that map it onto itself (a box's half turns about its axes, a square
    section's quarter turns), and the axis it is round about (a cylinder's, a sphere's z), if any."""
    if not all(abs(p.pos[0]) < 1e-9 and abs(p.pos[1]) < 1e-9 and abs(p.pos[2]) < 1e-9 for p in geo.parts):
        return [np.eye(3)], None
    turns = [np.eye(3), _turn(0, 180), _turn(1, 180), _turn(2, 180)]
    for axis in range(3):
        i, j = [k for k in range(3) if k != axis]
        if all(math.isclose(p.half[i], p.half[j], rel_tol=0.02) for p in geo.parts):
            turns += [t @ _turn(axis, 90) for t in turns[:4]]
    round_axes = {AXES[p.axis] if p.shape != "sphere" else 2 for p in geo.parts if p.shape in ("cylinder", "sphere")}
    round_about = round_axes.pop() if len(round_axes) == 1 and len(geo.parts) == 1 else None
    return turns, round_about


def _tilt(r: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, r[2, 2]))))


def _unroll(r: np.ndarray, axis: int) -> np.ndarray:
    """Turn a frame about its own `axis` (a round model's: the camera cannot see the turn) so that its z axis is
    as near the world's up as it can be or, turning about z, so that its x axis is as near the world's x."""
    i, j = [k for k in range(3) if k != axis]
    if axis == 2:
        local = r.T @ np.array([1.0, 0.0, 0.0])
        angle = math.atan2(local[j], local[i])
    else:  # z is the second of the two axes across this one
        local = r.T @ np.array([0.0, 0.0, 1.0])
        angle = math.atan2(-local[i], local[j])
    return r @ _turn_free(axis, angle)


def _turn_free(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def _yaw_abs(r: np.ndarray) -> float:
    return abs(math.atan2(r[1, 0], r[0, 0]))


def _yaw_rot(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_to_quat(r: np.ndarray) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(r).ravel())
    return q / np.linalg.norm(q)


def _ang_vel(r0: np.ndarray, r1: np.ndarray, dt: float) -> np.ndarray:
    """World-frame angular velocity turning r0 into r1 in dt."""
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(r1 @ r0.T).ravel())
    v = np.empty(3)
    mujoco.mju_quat2Vel(v, q, dt)
    return v


class PoseEstimator:
    """Tracks the objects of one evaluation world from its scene camera (see the module docstring)."""

    def __init__(self, model: mujoco.MjModel, geometry: dict[str, Geometry], object_geoms: dict[str, np.ndarray],
                 settings) -> None:  # noqa: ANN001 - a PerceptionSection
        self.s = settings
        self._renderer = SegDepthRenderer(model, settings.width, settings.height)
        self._geoms = {k: {int(g) for g in v} for k, v in object_geoms.items()}
        self._sdf = {k: model_sdf(g) for k, g in geometry.items()}
        self._geometry = geometry
        self._rng = np.random.default_rng(0)
        self._next_frame = -math.inf
        self._pending: deque[tuple[float, dict[str, Estimate]]] = deque()
        self.history: dict[str, list[Estimate]] = {k: [] for k in geometry}
        self.fit = FitSettings(loss_scale=0.002, inlier_tol=0.004, good_rms=0.0015, max_nfev=30)
        self.frames = 0

    def close(self) -> None:
        self._renderer.close()

    def reset(self) -> None:
        """Forget the tracks (the scene was put back): the next frame fits every object afresh."""
        self._pending.clear()
        self.history = {k: [] for k in self._geometry}
        self._next_frame = -math.inf

    def poses(self, data: mujoco.MjData) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """(pos, quat, lin_vel, ang_vel) of every object as the robot knows them at `data.time`."""
        t = float(data.time)
        if t >= self._next_frame - 1e-9:
            self._pending.append((t + self.s.latency_s, self._frame(data, t)))
            self._next_frame = t + 1.0 / self.s.rate_hz
        started = any(self.history.values())
        while self._pending and (self._pending[0][0] <= t + 1e-9 or not started):  # the first frame is waited for
            started = True
            _, found = self._pending.popleft()
            for k, e in found.items():
                self.history[k] = (self.history[k] + [e])[-2:]
        out = {}
        for k, h in self.history.items():
            if not h:
                raise PerceptionError(f"the camera has not seen {k!r} yet (latency {self.s.latency_s:g} s)")
            last = h[-1]
            lin, ang = np.zeros(3), np.zeros(3)
            if len(h) == 2 and h[1].t > h[0].t:
                dt = h[1].t - h[0].t
                lin, ang = (h[1].pos - h[0].pos) / dt, _ang_vel(h[0].rot, h[1].rot, dt)
            out[k] = (last.pos.copy(), rot_to_quat(last.rot), lin, ang)
        return out

    def _frame(self, data: mujoco.MjData, t: float) -> dict[str, Estimate]:
        view = self._renderer.view(data, "scene")
        depth = view.depth.astype(np.float64)
        depth = depth + self._rng.standard_normal(depth.shape) * self.s.depth_noise_m * depth * depth
        clouds = object_clouds([(view.camera, depth, view.seg)], self._geoms, max_points=MAX_POINTS)
        self.frames += 1
        found = {}
        for name, pts in clouds.items():
            if len(pts) < self.s.min_points:
                continue  # hidden: the last estimate stands
            e = self._fit(name, pts, t)
            if e is not None:
                found[name] = e
        known = {k for k, h in self.history.items() if h} | set(found) | {k for _, f in self._pending for k in f}
        unseen = sorted(set(self._geometry) - known)
        if unseen:
            raise PerceptionError(f"the scene camera does not see {', '.join(unseen)} "
                                  f"(fewer than {self.s.min_points} pixels of it)")
        return found

    def _canonical(self, name: str, frame: np.ndarray) -> np.ndarray:
        """Of the headings a symmetric model looks the same in (a box turned half a turn about its up axis, a
        square one a quarter turn), the one nearest the world's x axis: no camera can tell them apart."""
        turns, round_about = _symmetries(self._geometry[name])
        options = [frame @ t for t in turns]
        if round_about is not None:
            options = [_unroll(r, round_about) for r in options]
        return min(options, key=lambda r: (round(_tilt(r)), _yaw_abs(r)))

    def _fit(self, name: str, pts: np.ndarray, t: float) -> Estimate | None:
        track = self.history[name] or [e for _, f in self._pending for k, e in f.items() if k == name][-1:]
        if track:
            last = track[-1]
            starts = [(last.pos, last.rot)]
        else:  # first sight: upright at the cloud's centre, a few headings
            c = pts.mean(axis=0)
            starts = [(c, _yaw_rot(a)) for a in STARTS_DEG]
        fits = []
        for c0, r0 in starts:
            out = rigid_fit(pts, self._sdf[name], np.asarray(c0, float), r0, I3, I3, self.fit)
            if out is not None:
                fits.append((*fit_quality(out[2], self.fit), out[0], out[1]))
        if not fits:
            return None
        best_rms, best_in = min(f[0] for f in fits), max(f[1] for f in fits)
        # every fit as good as the best within noise (a box 2 mm longer than wide fits a quarter turn off as well)
        good = [f for f in fits if f[1] >= best_in - 0.02 and f[0] <= 1.05 * best_rms + 1e-4]
        rms, _, c, frame = min(good, key=lambda f: f[0]) if track else \
            min(((f[0], f[1], f[2], self._canonical(name, f[3])) for f in good), key=lambda f: _yaw_abs(f[3]))
        round_about = _symmetries(self._geometry[name])[1]
        if track and round_about is not None:  # a turn about a round model's axis never shows: none is reported
            frame = _unroll(frame, round_about)
        return Estimate(t=t, pos=np.asarray(c, float), rot=np.asarray(frame, float), rms_m=float(rms),
                        points=len(pts))
