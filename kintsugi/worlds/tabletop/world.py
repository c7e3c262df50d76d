"""The tabletop world: MuJoCo model + data, the arms' own sensors, renders, and ground truth.

`TabletopWorld` owns the physics. Methods get a `TabletopRobot` (robot.py), never
this object: `ground_truth()` (where objects really are, what is really held) exists
for scoring and for the explicit `perception.objects = "truth"` option only.
Names are resolved once; a wrong name raises with the names that exist.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Literal, Sequence

import mujoco
import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import UnknownNameError
from kintsugi.core.health import check_health
from kintsugi.perception.features import SegDepthRenderer
from kintsugi.worlds.tabletop.arm_model import JOINTS
from kintsugi.worlds.tabletop.config import ARMS, TabletopConfig
from kintsugi.worlds.tabletop.objects import Shape, shape_of
from kintsugi.worlds.tabletop.scene import CAMERAS, SceneExtra, build_scene_xml

View = Literal["rgb", "depth", "seg"]


class StartPose(StrictModel):
    """Where an object starts: on the table at (x, y), turned by yaw about the vertical."""

    x: float
    y: float
    yaw_deg: float = 0.0


class ObjectTruth(StrictModel):
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    axis: tuple[float, float, float]
    """The body's z axis in the world (a bottle's or cup's up direction)."""
    tilt_deg: float
    speed_m_s: float


class GroundTruth(StrictModel):
    """The simulator's state of the scene: scoring (and the truth-features option) only."""

    t: float
    objects: dict[str, ObjectTruth]
    held: dict[str, list[str]]
    """Per arm, the objects its two finger pads both touch."""


def resolve(model: mujoco.MjModel, objtype: mujoco.mjtObj, name: str) -> int:
    idx = mujoco.mj_name2id(model, objtype, name)
    if idx < 0:
        count = {mujoco.mjtObj.mjOBJ_BODY: model.nbody, mujoco.mjtObj.mjOBJ_JOINT: model.njnt,
                 mujoco.mjtObj.mjOBJ_SITE: model.nsite, mujoco.mjtObj.mjOBJ_GEOM: model.ngeom,
                 mujoco.mjtObj.mjOBJ_CAMERA: model.ncam, mujoco.mjtObj.mjOBJ_ACTUATOR: model.nu,
                 mujoco.mjtObj.mjOBJ_FLEX: model.nflex}[objtype]
        known = [mujoco.mj_id2name(model, objtype, i) for i in range(count)]
        raise UnknownNameError(f"no {objtype.name} named {name!r}; known: {', '.join(filter(None, known))}")
    return idx


@dataclass(frozen=True)
class ArmIds:
    """One arm's indices into the model, resolved once."""

    qpos: np.ndarray
    dof: np.ndarray
    act: np.ndarray
    grip_act: int
    finger_qpos: np.ndarray
    finger_dof: np.ndarray
    pads: tuple[int, int]
    tcp: int


def quat_to_axis(q: np.ndarray) -> np.ndarray:
    """The body z axis of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


class TabletopWorld:
    def __init__(self, cfg: TabletopConfig, objects: Sequence[str], start: dict[str, StartPose],
                 targets: Sequence[str] = (), extra: SceneExtra | None = None) -> None:
        self.cfg = cfg
        self.objects = tuple(objects)
        self.targets = tuple(targets)
        self.model = mujoco.MjModel.from_xml_string(build_scene_xml(cfg, self.objects, self.targets, extra))
        m = self.model
        o = mujoco.mjtObj
        self.flexes: dict[int, str] = {resolve(m, o.mjOBJ_FLEX, k): k for k in (extra.flexes if extra else ())}
        """Deformable objects (a cloth) by flex id: pad contacts report them by name like rigid objects."""
        self.arms: dict[str, ArmIds] = {}
        for arm in ARMS:
            joints = [resolve(m, o.mjOBJ_JOINT, f"{arm}_{j}") for j in JOINTS]
            fingers = [resolve(m, o.mjOBJ_JOINT, f"{arm}_finger_{s}") for s in ("l", "r")]
            self.arms[arm] = ArmIds(
                qpos=m.jnt_qposadr[joints].copy(), dof=m.jnt_dofadr[joints].copy(),
                act=np.array([resolve(m, o.mjOBJ_ACTUATOR, f"{arm}_{j}") for j in JOINTS]),
                grip_act=resolve(m, o.mjOBJ_ACTUATOR, f"{arm}_grip"),
                finger_qpos=m.jnt_qposadr[fingers].copy(), finger_dof=m.jnt_dofadr[fingers].copy(),
                pads=(resolve(m, o.mjOBJ_GEOM, f"{arm}_pad_l"), resolve(m, o.mjOBJ_GEOM, f"{arm}_pad_r")),
                tcp=resolve(m, o.mjOBJ_SITE, f"{arm}_tcp"),
            )
        self.bodies = {k: resolve(m, o.mjOBJ_BODY, k) for k in self.objects}
        self.shapes: dict[str, Shape] = {k: shape_of(k, cfg.objects) for k in self.objects}
        self._obj_qpos = {k: m.jnt_qposadr[resolve(m, o.mjOBJ_JOINT, k)] for k in self.objects}
        self._obj_dof = {k: m.jnt_dofadr[resolve(m, o.mjOBJ_JOINT, k)] for k in self.objects}
        self.geom_object = np.full(m.ngeom, -1)
        """Per geom: index into `self.objects`, or -1 (robot, table, regions)."""
        for i, k in enumerate(self.objects):
            self.geom_object[m.geom_bodyid == self.bodies[k]] = i
        for g in range(m.ngeom):  # regions painted beside an object are not part of it
            if (mujoco.mj_id2name(m, o.mjOBJ_GEOM, g) or "").startswith("target_"):
                self.geom_object[g] = -1
        self.cameras = {c: resolve(m, o.mjOBJ_CAMERA, c) for c in CAMERAS}
        self.table_geom = resolve(m, o.mjOBJ_GEOM, "table")
        self.data = mujoco.MjData(m)
        home = np.radians(cfg.robot.home_deg)
        for ids in self.arms.values():
            self.data.qpos[ids.qpos] = home
            self.data.ctrl[ids.act] = home
        for k in self.objects:
            p = start[k]
            a = self._obj_qpos[k]
            yaw = math.radians(p.yaw_deg)
            self.data.qpos[a:a + 3] = (p.x, p.y, self.shapes[k].rest_height + 0.0005)
            self.data.qpos[a + 3:a + 7] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        mujoco.mj_forward(m, self.data)
        self.steps = 0
        self.steps_per_tick = max(1, round(cfg.sim.control_dt_s / cfg.sim.timestep_s))
        self.watchers: list[Callable[[TabletopWorld], None]] = []
        """Called after every control tick: scoring monitors, disturbances, video."""
        self._forced_open: dict[str, float] = {}
        self._grip_ctrl = {arm: 0.0 for arm in ARMS}
        self._renderer: mujoco.Renderer | None = None
        self._seg_depth: SegDepthRenderer | None = None

    # --- stepping ----------------------------------------------------------
    def tick(self) -> None:
        """Advance one control period, then run the watchers."""
        for arm, until in list(self._forced_open.items()):
            if self.data.time >= until:
                del self._forced_open[arm]
                self.data.ctrl[self.arms[arm].grip_act] = self._grip_ctrl[arm]
        mujoco.mj_step(self.model, self.data, nstep=self.steps_per_tick)
        self.steps += self.steps_per_tick
        self.check_health()
        for watch in self.watchers:
            watch(self)

    def check_health(self) -> None:
        check_health(self.data)

    # --- commands ------------------------------------------------------------
    def set_joint_targets(self, arm: str, q: np.ndarray) -> None:
        self.data.ctrl[self.arms[arm].act] = q

    def set_grip(self, arm: str, closed: bool) -> None:
        """Command the gripper fully closed (squeezing with the force limit) or fully open."""
        self._grip_ctrl[arm] = self.cfg.robot.gripper_max_opening_m if closed else 0.0
        if arm not in self._forced_open:
            self.data.ctrl[self.arms[arm].grip_act] = self._grip_ctrl[arm]

    def set_grip_travel(self, arm: str, travel_m: float) -> None:
        """Command a partial closing travel (0 = open, the max opening = closed): a gentle close steps it up."""
        self._grip_ctrl[arm] = min(max(float(travel_m), 0.0), self.cfg.robot.gripper_max_opening_m)
        if arm not in self._forced_open:
            self.data.ctrl[self.arms[arm].grip_act] = self._grip_ctrl[arm]

    def force_open(self, arm: str, duration_s: float) -> None:
        """Disturbance: the gripper lets go for a while, whatever it is commanded (a slip)."""
        self._forced_open[arm] = float(self.data.time) + duration_s
        self.data.ctrl[self.arms[arm].grip_act] = 0.0

    # --- the robot's own sensors --------------------------------------------
    def joint_positions(self, arm: str) -> np.ndarray:
        return self.data.qpos[self.arms[arm].qpos].copy()

    def joint_velocities(self, arm: str) -> np.ndarray:
        return self.data.qvel[self.arms[arm].dof].copy()

    def joint_targets(self, arm: str) -> np.ndarray:
        return self.data.ctrl[self.arms[arm].act].copy()

    def tcp_pose(self, arm: str) -> tuple[np.ndarray, np.ndarray]:
        """Tool centre point position and rotation matrix (columns: gripper x, closing y, approach z)."""
        s = self.arms[arm].tcp
        return self.data.site_xpos[s].copy(), self.data.site_xmat[s].reshape(3, 3).copy()

    def gripper_opening(self, arm: str) -> float:
        q = self.data.qpos[self.arms[arm].finger_qpos]
        return float(self.cfg.robot.gripper_max_opening_m - q.sum())

    def flex_vertices(self, flex: int) -> np.ndarray:
        """(n, 3) world positions of a flex's vertices (ground truth: scoring and the truth option)."""
        a, n = self.model.flex_vertadr[flex], self.model.flex_vertnum[flex]
        return self.data.flexvert_xpos[a:a + n].copy()

    def flex_side(self, flex: int) -> int:
        """Vertices per side of a square grid flex."""
        return int(round(float(np.sqrt(self.model.flex_vertnum[flex]))))

    def gripper_commanded_closed(self, arm: str) -> bool:
        return self._grip_ctrl[arm] > 0.0

    def finger_speed(self, arm: str) -> float:
        return float(np.abs(self.data.qvel[self.arms[arm].finger_dof]).max())

    def pad_contacts(self, arm: str) -> tuple[dict[str, int], float]:
        """Objects touching this arm's finger pads (name -> number of pads touching), and the
        total normal force on the pads (N): what tactile pads on the fingers report."""
        pads = self.arms[arm].pads
        touching: dict[str, int] = {}
        force = 0.0
        buf = np.zeros(6)
        d = self.data
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            if self.flexes and (g1 in pads or g2 in pads) and max(c.flex) >= 0:
                pad = g1 if g1 in pads else g2
                mujoco.mj_contactForce(self.model, d, i, buf)
                force += abs(buf[0])
                name = self.flexes.get(int(max(c.flex)))
                if name is not None:
                    touching[name] = touching.get(name, 0) | 1 << pads.index(pad)
                continue
            if g1 in pads:
                other, pad = g2, g1
            elif g2 in pads:
                other, pad = g1, g2
            else:
                continue
            mujoco.mj_contactForce(self.model, d, i, buf)
            force += abs(buf[0])
            k = self.geom_object[other]
            if k >= 0:
                name = self.objects[k]
                touching.setdefault(name, 0)
                touching[name] |= 1 << pads.index(pad)
        return {k: bin(v).count("1") for k, v in touching.items()}, force

    # --- cameras -------------------------------------------------------------
    @property
    def renderer(self) -> mujoco.Renderer:
        """One offscreen renderer, kept alive for the world's life."""
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, self.cfg.cameras.height, self.cfg.cameras.width)
        return self._renderer

    @property
    def seg_depth_renderer(self) -> SegDepthRenderer:
        """Segmentation + depth in one pass (perception's renderer), kept alive for the world's life."""
        if self._seg_depth is None:
            self._seg_depth = SegDepthRenderer(self.model, self.cfg.cameras.width, self.cfg.cameras.height)
        return self._seg_depth

    def render(self, camera: str, view: View = "rgb") -> np.ndarray:
        """rgb (H, W, 3) uint8; depth (H, W) metres; seg (H, W) geom id per pixel, -1 for background."""
        if camera not in self.cameras:
            raise UnknownNameError(f"no camera named {camera!r}; known: {', '.join(self.cameras)}")
        r = self.renderer
        r.disable_depth_rendering()
        r.disable_segmentation_rendering()
        if view == "depth":
            r.enable_depth_rendering()
        elif view == "seg":
            r.enable_segmentation_rendering()
        r.update_scene(self.data, camera=self.cameras[camera])
        out = r.render()
        if view == "seg":
            ids = out[..., 0].astype(np.int32)
            ids[out[..., 1] != int(mujoco.mjtObj.mjOBJ_GEOM)] = -1
            return ids
        return out.copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._seg_depth is not None:
            self._seg_depth.close()
            self._seg_depth = None

    # --- ground truth: scoring and the truth-features option only ------------
    def ground_truth(self) -> GroundTruth:
        objs = {}
        for k in self.objects:
            a, v = self._obj_qpos[k], self._obj_dof[k]
            q = self.data.qpos[a + 3:a + 7]
            axis = quat_to_axis(q)
            objs[k] = ObjectTruth(
                pos=tuple(float(x) for x in self.data.qpos[a:a + 3]), quat=tuple(float(x) for x in q),
                axis=tuple(float(x) for x in axis),
                tilt_deg=math.degrees(math.acos(float(np.clip(axis[2], -1, 1)))),
                speed_m_s=float(np.linalg.norm(self.data.qvel[v:v + 3])))
        held = {arm: sorted(k for k, n in self.pad_contacts(arm)[0].items() if n == 2) for arm in ARMS}
        return GroundTruth(t=float(self.data.time), objects=objs, held=held)
