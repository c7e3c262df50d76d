"""The variables cost code reads, computed from a rollout batch or from one measured state.

Names and meanings are `kintsugi.methods.coral.formulate.variable_docs`; this module is their one
implementation for the control loop. Rollout variables are computed lazily (only what a
stage's function takes) and once per planning step. Nothing here reads the evaluation world:
rollouts come from the planning world, states from the robot's `Observation`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Callable, Iterator

import numpy as np

from kintsugi.methods.mppi.costs import EPS, Attractor, View
from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.objects import Geometry
from kintsugi.worlds.contact.world import Scene, up_axis, yaw_of


def static_env(scene: Scene, cfg: Any) -> dict[str, np.ndarray]:
    """Constants of the trial: known model sizes, fixtures, markers, robot facts."""
    env: dict[str, np.ndarray] = {
        "max_opening": np.asarray(cfg.effector.max_opening_m), "finger_length": np.asarray(cfg.effector.finger_length_m),
        "table_edge_x": np.asarray(cfg.table.edge_x_m)}
    for name, geo in scene.geometry.items():
        env[f"{name}_half"] = np.asarray(geo.parts[0].half, float)
    for name, f in scene.fixtures.items():
        env[f"{name}_lo"] = np.asarray(f.pos, float) - np.asarray(f.half, float)
        env[f"{name}_hi"] = np.asarray(f.pos, float) + np.asarray(f.half, float)
    for name, m in scene.markers.items():
        env[f"{name}_xy"], env[f"{name}_radius"] = np.asarray([m.x, m.y]), np.asarray(m.radius)
    return env


def rotation(quat: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices of (..., 4) unit quaternions (w, x, y, z), written into one array."""
    q = np.ascontiguousarray(np.moveaxis(quat, -1, 0))
    w, x, y, z = q
    xx, yy, zz, xy, xz, yz, wx, wy, wz = x * x, y * y, z * z, x * y, x * z, y * z, w * x, w * y, w * z
    out = np.empty((*quat.shape[:-1], 3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = 1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = 2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)
    out[..., 2, 0], out[..., 2, 1], out[..., 2, 2] = 2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)
    return out


def _bounds(geo: Geometry, pos: np.ndarray, quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World bounding box of an object made of boxes, for poses (..., 3), (..., 4): per part, its rotated
    centre +- |R| @ half extents (exact for boxes; matrix products instead of per-corner rotations)."""
    rot = rotation(quat)
    cols = [rot[..., :, j] for j in range(3)]
    abscols = [np.abs(c) for c in cols]
    lo = hi = None
    for part in geo.parts:
        centre = pos + sum(c * v for c, v in zip(cols, part.pos) if v)
        extent = sum(c * v for c, v in zip(abscols, part.half))
        lo = centre - extent if lo is None else np.minimum(lo, centre - extent)
        hi = centre + extent if hi is None else np.maximum(hi, centre + extent)
    return lo, hi


def contact_distance(attractor: Attractor, tcp: np.ndarray, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """Distance from the TCP to the nearest of the region's candidate targets, carried by the object's pose."""
    rot = rotation(quat)
    pts = attractor.targets  # (J, 3), object frame
    delta = tcp - pos
    local = np.einsum("...ji,...j->...i", rot, delta)  # the TCP in the object's frame: R^T (tcp - pos)
    # |local - p|^2 = |delta|^2 - 2 local.p + |p|^2, one small matrix product for every candidate at once
    d2 = (delta * delta).sum(axis=-1)[..., None] - 2.0 * (local @ pts.T) + (pts * pts).sum(axis=-1)
    return (np.sqrt(np.maximum(d2, 0.0) + EPS * EPS) - EPS).min(axis=-1)  # the smooth norm of Attractor.distance


def first_env(obs: Observation) -> dict[str, np.ndarray]:
    """The `first_*` constants of an attempt: where each object was when it began (a place's check that the
    other objects were left where they were reads them)."""
    return {f"first_{name}_pos": o.pos.copy() for name, o in obs.objects.items()}


def entry_env(obs: Observation, scene: Scene) -> dict[str, np.ndarray]:
    """The `start_*` constants of a stage, from the state it began in."""
    env = {"start_tcp": obs.ee[:3].copy(), "start_yaw": np.asarray(float(obs.ee[3]))}
    for name, o in obs.objects.items():
        lo, hi = _bounds(scene.geometry[name], o.pos, o.quat)
        env.update({f"start_{name}_pos": o.pos.copy(), f"start_{name}_yaw": np.asarray(float(yaw_of(o.quat))),
                    f"start_{name}_lo": lo, f"start_{name}_hi": hi})
    return env


class LazyEnv(Mapping):
    """A mapping computing each variable on first use."""

    def __init__(self, fixed: Mapping[str, np.ndarray], makers: dict[str, Callable[[], np.ndarray]]) -> None:
        self._fixed, self._makers, self._cache = fixed, makers, {}

    def __getitem__(self, key: str) -> np.ndarray:
        if key in self._fixed:
            return self._fixed[key]
        if key not in self._cache:
            self._cache[key] = self._makers[key]()
        return self._cache[key]

    def __contains__(self, key: object) -> bool:
        return key in self._fixed or key in self._makers

    def __iter__(self) -> Iterator[str]:
        return iter({*self._fixed, *self._makers})

    def __len__(self) -> int:
        return len({*self._fixed, *self._makers})


def rollout_env(view: View, scene: Scene, fixed: Mapping[str, np.ndarray], attractor: Attractor | None) -> LazyEnv:
    lay = view.layout
    makers: dict[str, Callable[[], np.ndarray]] = {
        "tcp": lambda: view.tcp, "yaw": lambda: view.yaw, "opening": lambda: view.opening,
        "force": lambda: view.force, "touch": lambda: view.touch, "ctrl": lambda: view.ctrl,
        "tcp_vel": lambda: view.batch.qvel[:, :, lay.ee_dof[:3]],
        "step_change": lambda: _step_change(view.ctrl),
    }
    for name in scene.geometry:
        box: dict[str, tuple[np.ndarray, np.ndarray]] = {}

        def bounds(n: str = name, memo: dict = box) -> tuple[np.ndarray, np.ndarray]:
            if "b" not in memo:
                memo["b"] = _bounds(scene.geometry[n], view.pos(n), view.quat(n))
            return memo["b"]

        makers.update({
            f"{name}_pos": (lambda n=name: view.pos(n)), f"{name}_vel": (lambda n=name: view.vel(n)),
            f"{name}_up": (lambda n=name: view.up(n)), f"{name}_yaw": (lambda n=name: yaw_of(view.quat(n))),
            f"{name}_lo": (lambda b=bounds: b()[0]), f"{name}_hi": (lambda b=bounds: b()[1]),
        })
    if attractor is not None:
        obj = attractor.region.obj
        makers["contact"] = lambda: contact_distance(attractor, view.tcp, view.pos(obj), view.quat(obj))
    return LazyEnv(fixed, makers)


def _step_change(ctrl: np.ndarray) -> np.ndarray:
    d = np.diff(ctrl[:, :, :3], axis=1, prepend=ctrl[:, :1, :3])
    return (d * d).sum(axis=-1)


def state_env(obs: Observation, scene: Scene, fixed: Mapping[str, np.ndarray], attractor: Attractor | None,
              elapsed: float) -> dict[str, np.ndarray]:
    """The same names for one measured state (no leading axes)."""
    env = dict(fixed)
    env.update({"tcp": obs.ee[:3], "yaw": np.asarray(float(obs.ee[3])), "opening": np.asarray(obs.opening),
                "force": obs.force, "touch": obs.touch, "ctrl": obs.ctrl, "tcp_vel": obs.ee_vel[:3],
                "step_change": np.asarray(0.0), "elapsed": np.asarray(elapsed)})
    for name, o in obs.objects.items():
        lo, hi = _bounds(scene.geometry[name], o.pos, o.quat)
        env.update({f"{name}_pos": o.pos, f"{name}_vel": o.lin_vel, f"{name}_up": up_axis(o.quat),
                    f"{name}_yaw": np.asarray(float(yaw_of(o.quat))), f"{name}_lo": lo, f"{name}_hi": hi,
                    f"{name}_spin": np.asarray(float(np.linalg.norm(o.ang_vel)))})
    if attractor is not None:
        o = obs.objects[attractor.region.obj]
        env["contact"] = np.asarray(float(np.linalg.norm(attractor.world_targets(o.pos, o.quat) - obs.ee[:3],
                                                         axis=-1).min()))
    return env
