"""Segmentation + depth renders to per-object world point clouds.

A pinhole `CameraModel` is the calibration a real robot would have: it is built
once from the camera's pose and field of view and never reads the scene.
MuJoCo's depth render is the z-depth along the camera axis in metres (distance
to the image plane, not ray length; tests check it against known geometry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import mujoco
import numpy as np

from kintsugi.core.errors import ConfigError, UnknownNameError

GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)
FLYING_TOL_M = 0.03
"""A pixel this much nearer the camera than every one of its neighbours is a flying pixel (left out)."""


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Pinhole model of a MuJoCo perspective camera; looks along its -z axis, y up, x right."""

    width: int
    height: int
    fovy_deg: float
    pos: np.ndarray  # (3,) world position
    xmat: np.ndarray  # (3, 3) columns: camera x, y, z axes in the world frame (MuJoCo cam_xmat)

    def __post_init__(self) -> None:
        if self.width < 1 or self.height < 1:
            raise ConfigError(f"camera image size must be positive, got {self.width}x{self.height}")
        if not 0.0 < self.fovy_deg < 180.0:
            raise ConfigError(f"camera fovy_deg must be in (0, 180), got {self.fovy_deg}")
        pos = np.array(self.pos, dtype=np.float64).reshape(-1)
        xmat = np.array(self.xmat, dtype=np.float64)
        if pos.shape != (3,) or xmat.size != 9:
            raise ConfigError(f"camera pos must have 3 values and xmat 9, got {pos.size} and {xmat.size}")
        xmat = xmat.reshape(3, 3)
        if not np.allclose(xmat.T @ xmat, np.eye(3), atol=1e-5):
            raise ConfigError("camera xmat is not a rotation matrix")
        pos.flags.writeable = False
        xmat.flags.writeable = False
        object.__setattr__(self, "pos", pos)
        object.__setattr__(self, "xmat", xmat)

    @classmethod
    def from_mujoco(
        cls, model: mujoco.MjModel, data: mujoco.MjData, camera: str | int, width: int, height: int
    ) -> CameraModel:
        """Calibration of a model camera (its pose as of the last mj_forward/mj_kinematics)."""
        cam_id = camera_id(model, camera)
        projection = getattr(model, "cam_projection", getattr(model, "cam_orthographic", None))
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, cam_id) or f"#{cam_id}"
        if projection is not None and int(projection[cam_id]) != 0:
            raise ConfigError(f"camera {name!r} is orthographic; only perspective cameras are supported")
        if np.any(model.cam_sensorsize[cam_id] > 0):
            raise ConfigError(f"camera {name!r} uses sensorsize/focal intrinsics; only fovy cameras are supported")
        return cls(
            width=int(width),
            height=int(height),
            fovy_deg=float(model.cam_fovy[cam_id]),
            pos=data.cam_xpos[cam_id].copy(),
            xmat=data.cam_xmat[cam_id].reshape(3, 3).copy(),
        )

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (square pixels; fovy spans the image height)."""
        return 0.5 * self.height / math.tan(math.radians(self.fovy_deg) / 2.0)

    @cached_property
    def _rays(self) -> np.ndarray:
        """(H, W, 3) world-frame direction per pixel, scaled so that a z-depth d gives the point pos + d * ray."""
        f = self.focal_px
        u = (np.arange(self.width) + 0.5 - self.width / 2.0) / f
        v = -(np.arange(self.height) + 0.5 - self.height / 2.0) / f  # row 0 is the top of the image
        cam = np.empty((self.height, self.width, 3))
        cam[..., 0] = u[None, :]
        cam[..., 1] = v[:, None]
        cam[..., 2] = -1.0
        return cam @ self.xmat.T

    def _check_depth(self, depth: np.ndarray) -> np.ndarray:
        depth = np.asarray(depth)
        if depth.shape != (self.height, self.width):
            raise ConfigError(f"depth image has shape {depth.shape}, camera expects {(self.height, self.width)}")
        return depth

    def points(self, depth: np.ndarray) -> np.ndarray:
        """(H, W) metric z-depth -> (H, W, 3) world points."""
        depth = self._check_depth(depth)
        return self.pos + self._rays * depth[..., None]

    def points_at(self, depth: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """World points of the given pixels only, (N, 3)."""
        depth = self._check_depth(depth)
        return self.pos + self._rays[rows, cols] * depth[rows, cols].astype(np.float64)[:, None]

    def project(self, points: np.ndarray) -> np.ndarray:
        """World points (N, 3) -> pixel coordinates (N, 2) as (col, row), pixel centres at +0.5."""
        cam = (np.asarray(points, dtype=np.float64) - self.pos) @ self.xmat
        f = self.focal_px
        col = self.width / 2.0 + f * cam[:, 0] / -cam[:, 2]
        row = self.height / 2.0 - f * cam[:, 1] / -cam[:, 2]
        return np.stack([col, row], axis=1)


class View(NamedTuple):
    """One camera's calibration with its depth and segmentation renders of the same instant."""

    camera: CameraModel
    depth: np.ndarray  # (H, W) float, metres
    seg: np.ndarray  # (H, W, 2) int (object id, object type) as MuJoCo renders it, or (H, W) geom ids


def camera_id(model: mujoco.MjModel, camera: str | int) -> int:
    """Camera index from a name or an index; UnknownNameError lists the cameras."""
    if isinstance(camera, str):
        cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
    else:
        cam_id = int(camera) if 0 <= int(camera) < model.ncam else -1
    if cam_id < 0:
        names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) or f"#{i}" for i in range(model.ncam)]
        raise UnknownNameError(f"unknown camera {camera!r}; cameras: {', '.join(names) or '(none)'}")
    return cam_id


def body_geom_ids(model: mujoco.MjModel, body: str | int) -> set[int]:
    """Geom ids of a body and of every body below it (what a segmentation mask of that object shows)."""
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body) if isinstance(body, str) else int(body)
    if not 0 <= root < model.nbody:
        raise UnknownNameError(f"unknown body {body!r}")
    inside = {root}
    for b in range(root + 1, model.nbody):  # parents always precede children
        if int(model.body_parentid[b]) in inside:
            inside.add(b)
    return {g for g in range(model.ngeom) if int(model.geom_bodyid[g]) in inside}


def _object_ids(seg: np.ndarray, shape: tuple[int, int], objtype: int) -> np.ndarray:
    seg = np.asarray(seg)
    if seg.shape == (*shape, 2):
        return np.where(seg[..., 1] == objtype, seg[..., 0], -1)
    if seg.shape == shape:
        return seg
    raise ConfigError(f"segmentation image has shape {seg.shape}, expected {shape} or {(*shape, 2)}")


def object_clouds(
    views: list[tuple[CameraModel, np.ndarray, np.ndarray]] | list[View],
    objects: dict[str, set[int]],
    max_points: int = 2000,
    objtype: int = GEOM,
    flying_tol_m: float | None = FLYING_TOL_M,
) -> dict[str, np.ndarray]:
    """Fused (N, 3) world cloud per object, from every view, in one pass over each image.

    Views are concatenated in order; above `max_points` an object's cloud is
    thinned to evenly spaced points (deterministic, keeps every view's share).
    Flying pixels (`flying_tol_m`, None keeps them) are left out first.
    """
    if max_points < 1:
        raise ConfigError(f"max_points must be >= 1, got {max_points}")
    names = list(objects)
    lut_size = 1 + max((max(ids) for ids in objects.values() if ids), default=0)
    lut = np.full(lut_size + 1, -1, dtype=np.int64)  # index objid + 1, so background -1 maps to -1
    for k, name in enumerate(names):
        for i in objects[name]:
            if i < 0:
                raise ConfigError(f"object {name!r} has a negative id {i}")
            if lut[i + 1] >= 0:
                raise ConfigError(f"id {i} belongs to both {names[lut[i + 1]]!r} and {name!r}")
            lut[i + 1] = k
    # Pass 1: each object's pixels (flat indices, raster order) per view; the small-int stable sort is a radix sort.
    pixels: list[list[tuple[int, np.ndarray]]] = [[] for _ in names]
    for v, (cam, depth, seg) in enumerate(views):
        cam._check_depth(depth)
        ids = _object_ids(seg, (cam.height, cam.width), objtype).ravel()
        owner = lut[np.clip(ids, -1, lut_size - 1) + 1]
        owner[ids >= lut_size] = -1
        if flying_tol_m is not None:
            owner[_flying(np.asarray(depth), flying_tol_m).ravel()] = -1
        flat = np.flatnonzero(owner >= 0)
        if flat.size == 0:
            continue
        who = owner[flat].astype(np.int16 if len(names) < 2**15 else np.int64)
        order = np.argsort(who, kind="stable")
        bounds = np.searchsorted(who[order], np.arange(len(names) + 1))
        for k in range(len(names)):
            if bounds[k + 1] > bounds[k]:
                pixels[k].append((v, flat[order[bounds[k] : bounds[k + 1]]]))
    # Pass 2: thin each object's pixels evenly over all its views, then back-project only those.
    out: dict[str, np.ndarray] = {}
    for k, name in enumerate(names):
        total = sum(len(f) for _, f in pixels[k])
        keep = np.linspace(0, total - 1, max_points).round().astype(np.int64) if total > max_points else None
        parts, start = [], 0
        for v, f in pixels[k]:
            if keep is not None:
                mine = keep[(keep >= start) & (keep < start + len(f))] - start
                start += len(f)
                f = f[mine]
            cam, depth, _ = views[v]
            rows, cols = np.divmod(f, cam.width)
            parts.append(cam.points_at(np.asarray(depth), rows, cols))
        cloud = np.concatenate(parts) if parts else np.empty((0, 3))
        out[name] = cloud[np.isfinite(cloud).all(axis=1)]
    return out


def _flying(depth: np.ndarray, tol: float) -> np.ndarray:
    """Flying pixels: nearer the camera than all 8 of their neighbours by more than `tol`.

    Seen on a lying spoon's silhouette: one pixel 12 cm above it, which made the spoon read 13 cm tall (a
    real depth camera has them too). No surface makes such a spike: a wall seen edge-on steps away from the
    camera between the rim and the table, and a part one pixel wide keeps its neighbours along it.
    """
    h, w = depth.shape
    padded = np.pad(depth, 1, constant_values=-np.inf)  # the image's border never makes a spike
    spike = np.ones((h, w), bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                spike &= depth < padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] - tol
    return spike


def object_cloud(
    views: list[tuple[CameraModel, np.ndarray, np.ndarray]] | list[View],
    ids: set[int],
    max_points: int = 2000,
    objtype: int = GEOM,
    flying_tol_m: float | None = FLYING_TOL_M,
) -> np.ndarray:
    """Fused (N, 3) world cloud of the pixels whose object id is in `ids` (geom ids by default)."""
    return object_clouds(views, {"object": set(ids)}, max_points, objtype, flying_tol_m)["object"]
