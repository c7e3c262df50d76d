"""The peg-insertion world: MuJoCo model + data, robot-side sensors, ground truth.

`PegWorld` owns the physics. Methods and reasoners only ever get a `PegRobot`
view (base pose, wrist compression/force, camera images and calibrations);
`ground_truth()` exists for scoring and lives on the world, not the robot.

Ground truth G: the peg tip is at least `scoring.min_depth_fraction` of the hole
depth below the board top and inside the opening's footprint, and the peg axis
is within `scoring.max_tilt_deg` of vertical. By default that is the largest tilt
a rigid peg seated that deep can have, atan(gap / depth), with `gap` the hole's
width minus the peg's along the direction the peg leans (the clearance across
flats): a peg tilted further is wedged, squeezed into the walls by the soft
contacts (measured: ~0.3 mm deep at ~500 N per contact), so it is jammed, not
inserted; there is deliberately no margin above the rigid bound.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError, UnknownNameError
from kintsugi.core.health import check_health
from kintsugi.perception.types import CameraCalibration
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.scene import build_mjcf
from kintsugi.worlds.peg.shapes import MM, gap_along, hole_for, peg_shape


HOME_POSE = np.array([-0.05, 0.16, 0.0])  # y, z (m), roll (rad)
SIDE_HIDES_GROUP, MAIN_HIDES_GROUP = 1, 2  # each camera hides the other's painted rim (seen edge-on)


class TrialParams(StrictModel):
    """The randomized truth of one trial (hidden from methods; recorded for analysis)."""

    shape: str
    hole_y_mm: float = 0.0
    hole_x_mm: float = 0.0
    friction_scale: float = 1.0
    grasp_angle_deg: float = 0.0


class GroundTruth(StrictModel):
    tip_depth_mm: float
    """Depth of the peg tip (axis centre of its bottom face) below the board top."""
    tip_offset_mm: float
    """Tip minus hole axis along y (the main camera's plane)."""
    tip_offset_x_mm: float
    """Tip minus hole axis along x (out of the main camera's plane)."""
    tilt_deg: float
    """Angle between the peg axis and vertical, any direction."""
    inside_hole: bool
    """The tip is below the board top and inside the opening's footprint."""
    min_depth_mm: float
    max_tilt_deg: float
    """The tilt bound G applied (it depends on the lean direction unless configured)."""
    success: bool


def _resolve(model: mujoco.MjModel, objtype: mujoco.mjtObj, name: str) -> int:
    idx = mujoco.mj_name2id(model, objtype, name)
    if idx < 0:
        count = {mujoco.mjtObj.mjOBJ_BODY: model.nbody, mujoco.mjtObj.mjOBJ_JOINT: model.njnt,
                 mujoco.mjtObj.mjOBJ_SITE: model.nsite, mujoco.mjtObj.mjOBJ_GEOM: model.ngeom,
                 mujoco.mjtObj.mjOBJ_CAMERA: model.ncam}[objtype]
        known = [mujoco.mj_id2name(model, objtype, i) for i in range(count)]
        raise UnknownNameError(f"no {objtype.name} named {name!r}; known: {', '.join(filter(None, known))}")
    return idx


class PegWorld:
    def __init__(self, cfg: PegTaskConfig, params: TrialParams) -> None:
        self.cfg = cfg
        self.params = params
        self.peg = peg_shape(params.shape, cfg)
        self.hole = hole_for(self.peg, cfg)
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(self.peg, self.hole, cfg))
        m = self.model
        obj = mujoco.mjtObj
        self._board = _resolve(m, obj.mjOBJ_BODY, "board")
        self._peg_body = _resolve(m, obj.mjOBJ_BODY, "peg")
        self._tip = _resolve(m, obj.mjOBJ_SITE, "peg_tip")
        self._camera = _resolve(m, obj.mjOBJ_CAMERA, "scene")
        self._side_camera = _resolve(m, obj.mjOBJ_CAMERA, "side") if cfg.camera.side_view else None
        self._mocap = m.body_mocapid[_resolve(m, obj.mjOBJ_BODY, "base")]
        jz = _resolve(m, obj.mjOBJ_JOINT, "wrist_z")
        self._qz = m.jnt_qposadr[jz]
        self._wrist_j = [_resolve(m, obj.mjOBJ_JOINT, j) for j in ("wrist_z", "wrist_roll", "wrist_pitch", "wrist_yaw")]
        self._wrist_q = [m.jnt_qposadr[j] for j in self._wrist_j]
        # Trial truth applied to the compiled model.
        m.body_pos[self._board, :2] = (params.hole_x_mm * MM, params.hole_y_mm * MM)
        for g in range(m.ngeom):
            if m.geom_bodyid[g] == self._board:
                m.geom_friction[g, 0] = cfg.hole.friction * params.friction_scale
        m.body_quat[self._peg_body] = _roll_quat(math.radians(params.grasp_angle_deg))
        sag = m.body_subtreemass[_resolve(m, obj.mjOBJ_BODY, "wrist_z")] * 9.81 / cfg.wrist.z_stiffness
        if cfg.wrist.gravity_preload:
            m.qpos_spring[self._qz] = sag
        self._z_rest = float(m.qpos_spring[self._qz] - sag)  # hanging equilibrium
        self.data = mujoco.MjData(m)
        self.set_base(HOME_POSE)
        mujoco.mj_forward(m, self.data)
        self._renderer: mujoco.Renderer | None = None
        self._views = {}
        for cam, hidden in ((self._camera, MAIN_HIDES_GROUP), (self._side_camera, SIDE_HIDES_GROUP)):
            if cam is not None:
                option = mujoco.MjvOption()
                option.geomgroup[hidden] = 0
                self._views[cam] = option
        self.min_depth = cfg.scoring.min_depth_fraction * cfg.hole.depth_mm * MM
        self.steps = 0

    # --- actuation -------------------------------------------------------
    def set_base(self, pose: np.ndarray) -> None:
        """Command the wrist base (mocap) to pose [y, z, roll] in metres/radians."""
        self.data.mocap_pos[self._mocap] = (0.0, pose[0], pose[1])
        self.data.mocap_quat[self._mocap] = _roll_quat(pose[2])

    def step(self, n: int) -> None:
        mujoco.mj_step(self.model, self.data, nstep=n)
        self.steps += n
        self.check_health()

    def check_health(self) -> None:
        check_health(self.data)

    # --- robot-side sensing ---------------------------------------------
    def base_pose(self) -> np.ndarray:
        pos = self.data.mocap_pos[self._mocap]
        q = self.data.mocap_quat[self._mocap]
        return np.array([pos[1], pos[2], 2 * math.atan2(q[1], q[0])])

    def wrist_compression(self) -> float:
        """Upward z-spring deflection from the hanging rest (m); positive = compressed.

        This is what a tared wrist force sensor reports, divided by the stiffness.
        """
        return float(self.data.qpos[self._qz] - self._z_rest)

    def wrist_deflection(self) -> np.ndarray:
        """Deflection of the four wrist springs (z m, roll, pitch, yaw rad) from rest."""
        return np.array([self.data.qpos[a] - self.model.qpos_spring[a] for a in self._wrist_q])

    def wrist_is_still(self, lin: float = 0.005, ang: float = 0.05) -> bool:
        """True when the wrist springs have stopped swinging (what a tared F/T sensor sees settle)."""
        v = [self.data.qvel[self.model.jnt_dofadr[j]] for j in self._wrist_j]
        return abs(v[0]) < lin and max(abs(x) for x in v[1:]) < ang

    @property
    def has_side_view(self) -> bool:
        return self._side_camera is not None

    def render(self) -> np.ndarray:
        """The main camera: the y-z plane seen from +x (image right = +y)."""
        return self._render(self._camera)

    def render_side(self) -> np.ndarray:
        """The optional side camera: the x-z plane seen from -y (image right = +x)."""
        if self._side_camera is None:
            raise ConfigError("this world has no side camera; set camera.side_view=true")
        return self._render(self._side_camera)

    def _render(self, camera: int) -> np.ndarray:
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, self.cfg.camera.height, self.cfg.camera.width)
        self._renderer.update_scene(self.data, camera=camera, scene_option=self._views[camera])
        return self._renderer.render().copy()

    def calibration(self) -> CameraCalibration:
        c = self.cfg.camera
        return CameraCalibration(
            width=c.width, height=c.height, px_per_mm=c.height / c.view_height_mm,
            cu=c.width / 2, cv=c.height / 2, y0_mm=c.center_y_mm, z0_mm=c.center_z_mm,
        )

    def side_calibration(self) -> CameraCalibration:
        """The side camera's calibration, same form as the main one but its horizontal axis is x:
        `to_plane(u, v)` returns (x, z) in mm, and `y0_mm` holds the image centre's x."""
        if self._side_camera is None:
            raise ConfigError("this world has no side camera; set camera.side_view=true")
        c = self.cfg.camera
        return CameraCalibration(
            width=c.width, height=c.height, px_per_mm=c.height / c.view_height_mm,
            cu=c.width / 2, cv=c.height / 2, y0_mm=c.center_x_mm, z0_mm=c.center_z_mm,
        )

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # --- ground truth: scoring only -------------------------------------
    def ground_truth(self) -> GroundTruth:
        tip = self.data.site_xpos[self._tip]
        dx, dy = tip[0] - self.params.hole_x_mm * MM, tip[1] - self.params.hole_y_mm * MM
        depth = -float(tip[2])
        inside = depth > 0 and self.hole.contains(dx, dy)
        ax, ay, az = self.data.xmat[self._peg_body][[2, 5, 8]]  # the peg's axis in the world
        lean = math.hypot(ax, ay)
        tilt = math.degrees(math.atan2(lean, az))
        max_tilt = self.max_tilt_deg((ax / lean, ay / lean) if lean > 1e-12 else (0.0, 1.0))
        return GroundTruth(
            tip_depth_mm=depth / MM, tip_offset_mm=dy / MM, tip_offset_x_mm=dx / MM, tilt_deg=tilt,
            inside_hole=bool(inside), min_depth_mm=self.min_depth / MM, max_tilt_deg=max_tilt,
            success=bool(inside and depth >= self.min_depth and tilt <= max_tilt),
        )

    def max_tilt_deg(self, lean: tuple[float, float]) -> float:
        """G's tilt bound for a peg leaning along the horizontal unit direction `lean` (x, y)."""
        fixed = self.cfg.scoring.max_tilt_deg
        if fixed is not None:
            return fixed
        return math.degrees(math.atan2(gap_along(self.peg, self.hole, lean), self.min_depth))


def _roll_quat(angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2), math.sin(angle / 2), 0.0, 0.0])
