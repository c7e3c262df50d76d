"""The two MuJoCo worlds of a contact trial, built from one scene.

- `EvaluationWorld`: the truth. Its masses and frictions are the trial's hidden draws;
  the robot acts in it, and only the task's scoring reads `ground_truth()` and the contact
  forces behind it.
- `PlanningWorld`: the method's mental model, what MPPI rolls out. Same structure, but its
  masses and frictions are BELIEFS (`set_beliefs`), and its state is copied in from what
  the robot observes (`sync`), never from the evaluation world.

Both share `Layout`: every index a cost or an observation needs, resolved once by name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import UnknownNameError
from kintsugi.core.health import check_health
from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.worlds.contact.objects import Fixture, Geometry, Marker, Physics, Placement
from kintsugi.worlds.contact.scene import ACTUATORS, EE_JOINTS, FINGERS, build_mjcf

GRAVITY = 9.81


class Scene(StrictModel):
    """One trial's layout: object shapes (known models), start poses, fixtures, markers."""

    geometry: dict[str, Geometry]
    start: dict[str, Placement]
    fixtures: dict[str, Fixture] = {}
    markers: dict[str, Marker] = {}


def resolve(model: mujoco.MjModel, objtype: mujoco.mjtObj, name: str) -> int:
    idx = mujoco.mj_name2id(model, objtype, name)
    if idx < 0:
        count = {mujoco.mjtObj.mjOBJ_BODY: model.nbody, mujoco.mjtObj.mjOBJ_JOINT: model.njnt,
                 mujoco.mjtObj.mjOBJ_SITE: model.nsite, mujoco.mjtObj.mjOBJ_GEOM: model.ngeom,
                 mujoco.mjtObj.mjOBJ_SENSOR: model.nsensor, mujoco.mjtObj.mjOBJ_ACTUATOR: model.nu}[objtype]
        known = [mujoco.mj_id2name(model, objtype, i) for i in range(count)]
        raise UnknownNameError(f"no {objtype.name} named {name!r}; known: {', '.join(filter(None, known))}")
    return idx


@dataclass(frozen=True)
class Layout:
    """Indices into qpos / qvel / sensordata, by name; identical in both worlds of a trial."""

    objects: tuple[str, ...]
    ee_qpos: np.ndarray  # x, y, z, yaw
    ee_dof: np.ndarray
    finger_qpos: np.ndarray
    finger_dof: np.ndarray
    obj_qpos: dict[str, int]  # free joint: pos (3) then quat (4)
    obj_dof: dict[str, int]  # lin vel (3) then ang vel (3)
    obj_body: dict[str, int]
    obj_geoms: dict[str, np.ndarray]
    effector_geoms: np.ndarray
    sensors: dict[str, slice]
    hand_weight_n: float
    """The hand's own weight below the F/T sensor: what the robot tares away."""

    @staticmethod
    def of(model: mujoco.MjModel, objects: tuple[str, ...]) -> Layout:
        o = mujoco.mjtObj
        ee = [resolve(model, o.mjOBJ_JOINT, j) for j in EE_JOINTS]
        fingers = [resolve(model, o.mjOBJ_JOINT, j) for j in FINGERS]
        for a in ACTUATORS:
            resolve(model, o.mjOBJ_ACTUATOR, a)
        obj_joint = {k: resolve(model, o.mjOBJ_JOINT, k) for k in objects}
        obj_body = {k: resolve(model, o.mjOBJ_BODY, k) for k in objects}
        sensors = {}
        for i in range(model.nsensor):
            adr, dim = int(model.sensor_adr[i]), int(model.sensor_dim[i])
            sensors[mujoco.mj_id2name(model, o.mjOBJ_SENSOR, i)] = slice(adr, adr + dim)
        hand = resolve(model, o.mjOBJ_BODY, "hand")
        eff_bodies = {hand} | {resolve(model, o.mjOBJ_BODY, f) for f in FINGERS}
        return Layout(
            objects=objects,
            ee_qpos=model.jnt_qposadr[ee].copy(), ee_dof=model.jnt_dofadr[ee].copy(),
            finger_qpos=model.jnt_qposadr[fingers].copy(), finger_dof=model.jnt_dofadr[fingers].copy(),
            obj_qpos={k: int(model.jnt_qposadr[j]) for k, j in obj_joint.items()},
            obj_dof={k: int(model.jnt_dofadr[j]) for k, j in obj_joint.items()},
            obj_body=obj_body,
            obj_geoms={k: np.flatnonzero(model.geom_bodyid == b) for k, b in obj_body.items()},
            effector_geoms=np.flatnonzero(np.isin(model.geom_bodyid, list(eff_bodies))),
            sensors=sensors,
            hand_weight_n=float(model.body_subtreemass[hand] * GRAVITY),
        )


def tared_force_world(raw: np.ndarray, yaw: np.ndarray, hand_weight_n: float) -> np.ndarray:
    """The force the hand exerts on its surroundings, in the world frame, from the F/T sensor.

    `raw` (..., 3) is the sensor's reading in the hand frame (the wrist's pull on the hand);
    rotated to the world by the hand's yaw and with the hand's own weight tared away.
    Works on one reading or on a whole (K, T, 3) batch of rollouts.
    """
    c, s = np.cos(yaw), np.sin(yaw)
    fx = c * raw[..., 0] - s * raw[..., 1]
    fy = s * raw[..., 0] + c * raw[..., 1]
    return np.stack([fx, fy, raw[..., 2] - hand_weight_n], axis=-1)


class ContactWorld:
    """One MuJoCo instance of a trial's scene; `physics` are truth or beliefs (see subclasses)."""

    def __init__(self, cfg: ContactConfig, scene: Scene, physics: dict[str, Physics], timestep: float) -> None:
        self.cfg = cfg
        self.scene = scene
        xml = build_mjcf(cfg, scene.geometry, physics, scene.start, scene.fixtures, scene.markers, timestep)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self.layout = Layout.of(self.model, tuple(scene.geometry))
        self.steps = 0
        home = np.array([*cfg.effector.home_m, 0.0])
        self.data.qpos[self.layout.ee_qpos] = home
        self.data.qpos[self.layout.finger_qpos] = cfg.effector.max_opening_m / 2
        self.data.ctrl[:] = [*home, cfg.effector.max_opening_m]
        mujoco.mj_forward(self.model, self.data)

    def step(self, n: int = 1) -> None:
        mujoco.mj_step(self.model, self.data, nstep=n)
        self.steps += n
        self.check_health()

    def check_health(self) -> None:
        check_health(self.data)

    @property
    def ctrlrange(self) -> np.ndarray:
        return self.model.actuator_ctrlrange.copy()

    def physics_of(self, name: str) -> Physics:
        """The mass and friction this model holds for an object (truth here, beliefs in a planning world)."""
        geoms = self.layout.obj_geoms[name]
        return Physics(mass_kg=float(self.model.body_mass[self.layout.obj_body[name]]),
                       friction=float(self.model.geom_friction[geoms[0], 0]))


class EvaluationWorld(ContactWorld):
    """The truth: the trial's drawn masses and frictions at the fine timestep."""

    def __init__(self, cfg: ContactConfig, scene: Scene, truth: dict[str, Physics]) -> None:
        super().__init__(cfg, scene, truth, cfg.sim.timestep_s)
        self._renderer: mujoco.Renderer | None = None

    def pusher_force(self, name: str) -> np.ndarray:
        """Ground truth (scoring only): total contact force the effector exerts on object `name`, world frame."""
        lay, m, d = self.layout, self.model, self.data
        eff, geoms = set(lay.effector_geoms.tolist()), set(lay.obj_geoms[name].tolist())
        total = np.zeros(3)
        buf = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            if g1 in eff and g2 in geoms:
                sign = 1.0  # contact frame normal points from geom1 to geom2: effector -> object
            elif g2 in eff and g1 in geoms:
                sign = -1.0
            else:
                continue
            mujoco.mj_contactForce(m, d, i, buf)
            frame = c.frame.reshape(3, 3)
            total += sign * (frame.T @ buf[:3])
        return total

    def pinched(self, name: str) -> bool:
        """Ground truth: both finger pads touch the object."""
        return len(self._pads_on(name)) == 2

    def touching_pads(self, name: str) -> bool:
        """Ground truth: at least one finger pad touches the object."""
        return bool(self._pads_on(name))

    def _pads_on(self, name: str) -> set[int]:
        lay, m, d = self.layout, self.model, self.data
        geoms = set(lay.obj_geoms[name].tolist())
        fingers = [resolve(m, mujoco.mjtObj.mjOBJ_GEOM, f) for f in FINGERS]
        seen = set()
        for i in range(d.ncon):
            g1, g2 = int(d.contact[i].geom1), int(d.contact[i].geom2)
            for f in fingers:
                if (g1 == f and g2 in geoms) or (g2 == f and g1 in geoms):
                    seen.add(f)
        return seen

    def in_contact(self, name: str, other: str) -> bool:
        """Ground truth: object `name` touches `other` (another object or a fixture, by name)."""
        lay, m, d = self.layout, self.model, self.data
        mine = set(lay.obj_geoms[name].tolist())
        if other in lay.obj_geoms:
            theirs = set(lay.obj_geoms[other].tolist())
        else:
            theirs = {resolve(m, mujoco.mjtObj.mjOBJ_GEOM, other)}
        for i in range(d.ncon):
            g1, g2 = int(d.contact[i].geom1), int(d.contact[i].geom2)
            if (g1 in mine and g2 in theirs) or (g2 in mine and g1 in theirs):
                return True
        return False

    def object_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        a = self.layout.obj_qpos[name]
        return self.data.qpos[a:a + 3].copy(), self.data.qpos[a + 3:a + 7].copy()

    def object_velocity(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        v = self.layout.obj_dof[name]
        return self.data.qvel[v:v + 3].copy(), self.data.qvel[v + 3:v + 6].copy()

    def renderer(self) -> mujoco.Renderer:
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, self.cfg.camera.height, self.cfg.camera.width)
        return self._renderer

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


class PlanningWorld(ContactWorld):
    """The method's model of the world: masses and frictions are beliefs; the state comes from observations."""

    def __init__(self, cfg: ContactConfig, scene: Scene, beliefs: dict[str, Physics],
                 timestep: float | None = None) -> None:
        super().__init__(cfg, scene, beliefs, timestep or cfg.sim.planning_timestep_s)
        lay = self.layout
        self._nominal_mass = {k: float(self.model.body_mass[b]) for k, b in lay.obj_body.items()}
        self._nominal_inertia = {k: self.model.body_inertia[b].copy() for k, b in lay.obj_body.items()}

    def set_beliefs(self, beliefs: dict[str, Physics]) -> None:
        """Write new beliefs into the model (inertia scales with mass: the shape is known), then mj_setConst.

        A `MPPI`/`RolloutEngine` sharing this model sees them on its next batch.
        """
        m, lay = self.model, self.layout
        for name, phys in beliefs.items():
            b = lay.obj_body[name]
            scale = phys.mass_kg / self._nominal_mass[name]
            m.body_mass[b] = phys.mass_kg
            m.body_inertia[b] = self._nominal_inertia[name] * scale
            m.geom_friction[lay.obj_geoms[name], 0] = phys.friction
        mujoco.mj_setConst(m, self.data)

    def beliefs(self) -> dict[str, Physics]:
        return {k: self.physics_of(k) for k in self.layout.objects}

    def sync(self, ee_qpos: np.ndarray, ee_qvel: np.ndarray, finger_q: np.ndarray, finger_v: np.ndarray,
             objects: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]], ctrl: np.ndarray,
             t: float) -> mujoco.MjData:
        """Set the planning state from observations: joints (proprioception), tracked object poses
        and velocities, the last command. Returns the data MPPI plans from."""
        lay, d = self.layout, self.data
        d.qpos[lay.ee_qpos] = ee_qpos
        d.qvel[lay.ee_dof] = ee_qvel
        d.qpos[lay.finger_qpos] = finger_q
        d.qvel[lay.finger_dof] = finger_v
        for k, (pos, quat, lin, ang) in objects.items():
            a, v = lay.obj_qpos[k], lay.obj_dof[k]
            d.qpos[a:a + 3], d.qpos[a + 3:a + 7] = pos, quat
            d.qvel[v:v + 3], d.qvel[v + 3:v + 6] = lin, ang
        d.ctrl[:] = ctrl
        d.time = t
        d.qacc_warmstart[:] = 0.0
        mujoco.mj_forward(self.model, d)
        return d


def yaw_of(quat: np.ndarray) -> np.ndarray:
    """Yaw (rad) of (..., 4) quaternions (w, x, y, z): the heading of the body x axis."""
    w, x, y, z = (quat[..., i] for i in range(4))
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def up_axis(quat: np.ndarray) -> np.ndarray:
    """(..., 3) body z axis in the world of (..., 4) quaternions."""
    w, x, y, z = (quat[..., i] for i in range(4))
    return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=-1)


def x_axis(quat: np.ndarray) -> np.ndarray:
    w, x, y, z = (quat[..., i] for i in range(4))
    return np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=-1)


def rotate(quat: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate (..., 3) vectors by (..., 4) quaternions."""
    w = quat[..., :1]
    u = quat[..., 1:]
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def tilt_deg(quat: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(up_axis(quat)[..., 2], -1.0, 1.0)))


def angle_wrap(a: np.ndarray | float) -> np.ndarray | float:
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi
