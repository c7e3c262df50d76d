"""MJCF for the soft-wrist peg-insertion world, generated from the typed config.

Layout (metres): the board's top surface is the plane z = 0 and the nominal
hole axis is at y = 0; the camera looks along -x at the y-z task plane, so
image right is +y and image up is +z. The optional side camera looks along +y
at the x-z plane (image right +x); each camera sees the hole's section painted
red on the board face in front of it, and hides the other's paint (geom group). The wrist base is a mocap body (an
ideal position-controlled arm); four spring joints (z slide, roll, pitch,
yaw) connect it to the gripper, which holds the peg rigidly.
"""

from __future__ import annotations

import math

from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.shapes import MM, HoleShape, PegShape

BOARD_HALF_X = 0.08
BOARD_HALF_Y = 0.16
PLATE_HALF_CUT = 0.04  # square cut-out of the top plate, filled by the hole's wall boxes
WALL_THICK = 0.05
WALL_HALF_LEN = 0.078
PEG_RGBA = "0 0.85 0.85 1"
HOLE_RGBA = "0.9 0.05 0.05 1"
BOARD_RGBA = "0.55 0.55 0.55 1"
GRIPPER_RGBA = "0.22 0.22 0.25 1"


def _f(*xs: float) -> str:
    return " ".join(f"{x:.6g}" for x in xs)


def _board_geoms(hole: HoleShape, cfg: PegTaskConfig) -> list[str]:
    depth = cfg.hole.depth_mm * MM
    floor_t = 0.01
    mu = cfg.hole.friction
    common = f'class="board" friction="{mu:.6g} 0.005 0.0001"'
    geoms = []
    # Top plate around the cut-out: four boxes.
    hz = depth / 2
    cz = -depth / 2
    side_w = (BOARD_HALF_Y - PLATE_HALF_CUT) / 2
    for sgn in (-1, 1):
        geoms.append(f'<geom name="plate_y{sgn:+d}" type="box" size="{_f(BOARD_HALF_X, side_w, hz)}" '
                     f'pos="{_f(0, sgn * (PLATE_HALF_CUT + side_w), cz)}" {common}/>')
        xw = (BOARD_HALF_X - PLATE_HALF_CUT) / 2
        geoms.append(f'<geom name="plate_x{sgn:+d}" type="box" size="{_f(xw, PLATE_HALF_CUT, hz)}" '
                     f'pos="{_f(sgn * (PLATE_HALF_CUT + xw), 0, cz)}" {common}/>')
    # Hole walls: one box per half-plane, inner face on the hole's side.
    n = len(hole.sides)
    front = BOARD_HALF_X  # the rim must be painted in front of every wall box
    side = -BOARD_HALF_Y  # likewise the side view's rim, on the -y face
    for k, (angle, inset) in enumerate(hole.sides):
        ny, nx = math.cos(angle), math.sin(angle)
        d = inset + WALL_THICK / 2
        # Long enough to close the ring between neighbours, short enough to stay inside the board.
        half_len = min(WALL_HALF_LEN, (inset + WALL_THICK) * math.tan(math.pi / n) + 0.005)
        front = max(front, nx * d + half_len * abs(ny) + WALL_THICK / 2 * abs(nx))
        side = min(side, ny * d - half_len * abs(nx) - WALL_THICK / 2 * abs(ny))
        geoms.append(
            f'<geom name="wall{k}" type="box" size="{_f(half_len, WALL_THICK / 2, hz)}" '
            f'pos="{_f(nx * d, ny * d, cz)}" euler="0 0 {-angle:.6g}" {common}/>'
        )
    # Floor under the whole board (the hole's bottom).
    geoms.append(f'<geom name="floor" type="box" size="{_f(BOARD_HALF_X, BOARD_HALF_Y, floor_t / 2)}" '
                 f'pos="{_f(0, 0, -depth - floor_t / 2)}" {common}/>')
    # Red rim: the hole's section painted on the board's front face (visual only).
    y0, y1 = hole.y_range
    geoms.append(
        f'<geom name="hole_rim" type="box" size="{_f(0.0005, (y1 - y0) / 2, hz)}" '
        f'pos="{_f(front + 0.001, (y0 + y1) / 2, cz)}" rgba="{HOLE_RGBA}" contype="0" conaffinity="0" group="1"/>'
    )
    if cfg.camera.side_view:
        x0, x1 = hole.x_range
        geoms.append(
            f'<geom name="hole_rim_side" type="box" size="{_f((x1 - x0) / 2, 0.0005, hz)}" '
            f'pos="{_f((x0 + x1) / 2, side - 0.001, cz)}" rgba="{HOLE_RGBA}" contype="0" conaffinity="0" group="2"/>'
        )
    return geoms


def _peg_geom(peg: PegShape, cfg: PegTaskConfig) -> tuple[str, str]:
    """(asset xml, geom xml) of the peg, its top at the body origin, axis along -z."""
    half_len = cfg.peg.length_mm / 2 * MM
    common = (f'name="peg" pos="0 0 {-half_len:.6g}" rgba="{PEG_RGBA}" mass="{cfg.peg.mass_kg:.6g}" '
              f'friction="{cfg.peg.friction:.6g} 0.005 0.0001"')
    if peg.kind == "cylinder":
        return "", f'<geom type="cylinder" size="{_f(peg.half_y, half_len)}" {common}/>'
    if peg.kind == "box":
        return "", f'<geom type="box" size="{_f(peg.half_x, peg.half_y, half_len)}" {common}/>'
    verts = " ".join(_f(*v) for v in peg.prism_vertices(half_len))
    return f'<mesh name="peg_mesh" vertex="{verts}"/>', f'<geom type="mesh" mesh="peg_mesh" {common}/>'


def build_mjcf(peg: PegShape, hole: HoleShape, cfg: PegTaskConfig) -> str:
    w = cfg.wrist
    cam = cfg.camera
    solref = f"{cfg.sim.contact_timeconst_s:.6g} 1"
    peg_asset, peg_geom = _peg_geom(peg, cfg)
    hinge = w.hinge_to_grasp_mm * MM
    small = 'mass="0.01" diaginertia="1e-5 1e-5 1e-5"'
    finger_h = cfg.grasp.depth_mm * MM / 2 + 0.005
    finger_y = peg.half_y + 0.006
    board = "\n      ".join(_board_geoms(hole, cfg))
    side_camera = (
        f'<camera name="side" mode="fixed" pos="{_f(cam.center_x_mm * MM, -0.6, cam.center_z_mm * MM)}" '
        f'xyaxes="1 0 0 0 0 1" projection="orthographic" fovy="{cam.view_height_mm * MM:.6g}"/>'
        if cam.side_view else ""
    )
    return f"""
<mujoco model="peg_insertion">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{cfg.sim.timestep_s:.6g}" gravity="0 0 -9.81" cone="elliptic" noslip_iterations="{cfg.sim.noslip_iterations}">
    <flag multiccd="enable"/>
  </option>
  <size memory="8M"/>
  <visual>
    <quality offsamples="0" shadowsize="0"/>
    <global offwidth="{cam.width}" offheight="{cam.height}"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.5 0.5 0.5" specular="0 0 0"/>
  </visual>
  <default>
    <geom solref="{solref}" solimp="0.95 0.99 0.0005" condim="3"/>
    <default class="board"><geom rgba="{BOARD_RGBA}"/></default>
  </default>
  <asset>{peg_asset}</asset>
  <worldbody>
    <camera name="scene" mode="fixed" pos="{_f(0.6, cam.center_y_mm * MM, cam.center_z_mm * MM)}"
            xyaxes="0 1 0 0 0 1" projection="orthographic" fovy="{cam.view_height_mm * MM:.6g}"/>
    {side_camera}
    <body name="board" pos="0 0 0">
      {board}
    </body>
    <body name="base" mocap="true" pos="0 -0.05 0.2">
      <geom name="base_flange" type="cylinder" size="0.03 0.01" pos="0 0 0.01" rgba="{GRIPPER_RGBA}" contype="0" conaffinity="0"/>
      <body name="wrist_z">
        <inertial pos="0 0 0" {small}/>
        <joint name="wrist_z" type="slide" axis="0 0 1" stiffness="{w.z_stiffness:.6g}" damping="{w.z_damping:.6g}"/>
        <body name="wrist_roll">
          <inertial pos="0 0 0" {small}/>
          <joint name="wrist_roll" type="hinge" axis="1 0 0" stiffness="{w.roll_stiffness:.6g}" damping="{w.roll_damping:.6g}"/>
          <body name="wrist_pitch">
            <inertial pos="0 0 0" {small}/>
            <joint name="wrist_pitch" type="hinge" axis="0 1 0" stiffness="{w.pitch_stiffness:.6g}" damping="{w.pitch_damping:.6g}"/>
            <body name="gripper" pos="0 0 {-hinge:.6g}">
              <joint name="wrist_yaw" type="hinge" axis="0 0 1" stiffness="{w.yaw_stiffness:.6g}" damping="{w.yaw_damping:.6g}"/>
              <geom name="palm" type="box" size="{_f(0.02, finger_y + 0.006, 0.008)}" pos="0 0 {0.008 + 0.004:.6g}" mass="{w.gripper_mass_kg * 0.6:.6g}" rgba="{GRIPPER_RGBA}"/>
              <geom name="finger_l" type="box" size="{_f(0.012, 0.004, finger_h)}" pos="{_f(0, -finger_y, 0.004 - finger_h)}" mass="{w.gripper_mass_kg * 0.2:.6g}" rgba="{GRIPPER_RGBA}"/>
              <geom name="finger_r" type="box" size="{_f(0.012, 0.004, finger_h)}" pos="{_f(0, finger_y, 0.004 - finger_h)}" mass="{w.gripper_mass_kg * 0.2:.6g}" rgba="{GRIPPER_RGBA}"/>
              <body name="peg" pos="0 0 0">
                {peg_geom}
                <site name="peg_top" pos="0 0 0" size="0.002"/>
                <site name="peg_tip" pos="0 0 {-cfg.peg.length_mm * MM:.6g}" size="0.002"/>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
