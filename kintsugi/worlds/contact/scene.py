"""MJCF of the contact world, generated from the typed config and one trial's scene.

The same builder makes the evaluation world (physics = truth, fine timestep) and the
planning world (physics = beliefs, MPPI's coarser timestep): they differ only in those
numbers, never in structure, so a state copies from one to the other index for index.

Frictions: MuJoCo lets the geom with the higher `priority` set a contact's friction.
Finger pads (2) > objects (1) > table, walls (0), so an object's `friction` is exactly its
friction against the table and walls, and a pinch always uses the pads' friction. Round parts
(cylinder, sphere, capsule) also set their rolling and torsional resistance (condim 6).
"""

from __future__ import annotations

import math

from kintsugi.worlds.contact.config import ContactConfig
from kintsugi.worlds.contact.objects import Fixture, Geometry, Marker, Physics, Placement

FINGERS = ("finger_l", "finger_r")
EE_JOINTS = ("ee_x", "ee_y", "ee_z", "ee_yaw")
ACTUATORS = ("x", "y", "z", "yaw", "grip")
PALM_HALF_Z = 0.01
EE_RGBA = "0.25 0.25 0.28 1"
PAD_RGBA = "0.15 0.15 0.15 1"
ROLLING_M = 0.001
"""Rolling resistance (m) of a round part (cylinder, sphere, capsule) on the table: a pushed ball or lying
cylinder rolls and comes to rest, as on a real table top, instead of rolling on for ever."""
TORSION_M = 0.005


def _f(*xs: float) -> str:
    return " ".join(f"{x:.6g}" for x in xs)


def _object_body(name: str, geo: Geometry, phys: Physics, place: Placement) -> str:
    total = sum(geo.volumes)
    geoms = []
    for i, (part, vol) in enumerate(zip(geo.parts, geo.volumes)):
        gname = name if len(geo.parts) == 1 else f"{name}_{i}"
        kind, size, turn = part.mjcf()
        roll = "" if kind == "box" else f' condim="6" friction="{phys.friction:.6g} {TORSION_M:.6g} {ROLLING_M:.6g}"'
        fric = "" if roll else f' friction="{phys.friction:.6g} 0.005 0.0001"'
        geoms.append(f'<geom name="{gname}" type="{kind}" size="{size}"{turn} pos="{_f(*part.pos)}" '
                     f'mass="{phys.mass_kg * vol / total:.6g}"{fric}{roll} '
                     f'priority="1" rgba="{_f(*geo.rgba)}"/>')
    return (f'<body name="{name}" pos="{_f(place.x, place.y, geo.rest_z)}" quat="{_f(*place.quat())}">'
            f'<freejoint name="{name}"/>{"".join(geoms)}</body>')


def _effector(cfg: ContactConfig) -> tuple[str, str]:
    """(worldbody xml, actuator + equality + tendon xml) of the end effector."""
    e = cfg.effector
    fl, fw, ft = e.finger_length_m, e.finger_width_m, e.finger_thickness_m
    half_open = e.max_opening_m / 2
    palm_y = half_open + ft + 0.005
    fingers = []
    for name, sgn in (("finger_l", 1), ("finger_r", -1)):
        fingers.append(
            f'<body name="{name}" gravcomp="1">'
            f'<joint name="{name}" type="slide" axis="0 {sgn} 0" range="0 {half_open:.6g}" damping="2" armature="0.01"/>'
            f'<geom name="{name}" type="box" size="{_f(fw / 2, ft / 2, fl / 2)}" pos="{_f(0, sgn * ft / 2, fl / 2)}" '
            f'mass="{e.finger_mass_kg:.6g}" friction="{e.pad_friction:.6g} {e.pad_torsion_m:.6g} 0.0001" condim="4" priority="2" '
            f'rgba="{PAD_RGBA}"/>'
            f'<site name="pad_{name[-1]}" type="box" size="{_f(fw / 2 + 0.001, 0.004, fl / 2 + 0.001)}" '
            f'pos="{_f(0, 0, fl / 2)}" rgba="0 0 0 0"/>'
            f'</body>')
    body = f"""
    <body name="ee_x" gravcomp="1">
      <joint name="ee_x" type="slide" axis="1 0 0" range="{_f(*e.workspace_x_m)}" armature="{e.armature:.6g}"/>
      <inertial pos="0 0 0" mass="0.5" diaginertia="1e-3 1e-3 1e-3"/>
      <body name="ee_y" gravcomp="1">
        <joint name="ee_y" type="slide" axis="0 1 0" range="{_f(*e.workspace_y_m)}" armature="{e.armature:.6g}"/>
        <inertial pos="0 0 0" mass="0.5" diaginertia="1e-3 1e-3 1e-3"/>
        <body name="ee_z" gravcomp="1">
          <joint name="ee_z" type="slide" axis="0 0 1" range="{_f(*e.workspace_z_m)}" armature="{e.armature:.6g}"/>
          <inertial pos="0 0 0" mass="0.5" diaginertia="1e-3 1e-3 1e-3"/>
          <body name="hand" gravcomp="1">
            <joint name="ee_yaw" type="hinge" axis="0 0 1" range="{_f(*[math.radians(a) for a in e.yaw_range_deg])}" armature="{e.armature * 0.02:.6g}"/>
            <geom name="palm" type="box" size="{_f(fw / 2 + 0.004, palm_y, PALM_HALF_Z)}" pos="{_f(0, 0, fl + PALM_HALF_Z)}" mass="{e.hand_mass_kg:.6g}" rgba="{EE_RGBA}" priority="2" friction="{e.pad_friction:.6g} 0.01 0.0001"/>
            <geom name="wrist" type="cylinder" size="0.018 0.03" pos="{_f(0, 0, fl + 2 * PALM_HALF_Z + 0.03)}" mass="0.01" rgba="{EE_RGBA}" contype="0" conaffinity="0"/>
            <site name="tcp" pos="0 0 0" size="0.004" rgba="1 1 0 0"/>
            <site name="ft" pos="{_f(0, 0, fl + 2 * PALM_HALF_Z)}" size="0.005" rgba="0 0 0 0"/>
            {"".join(fingers)}
          </body>
        </body>
      </body>
    </body>"""
    kp, zeta, f = e.kp_n_per_m, e.damping_ratio, e.force_limit_n
    yr = _f(*[math.radians(a) for a in e.yaw_range_deg])
    act = f"""
  <tendon><fixed name="grip"><joint joint="finger_l" coef="1"/><joint joint="finger_r" coef="1"/></fixed></tendon>
  <equality><joint joint1="finger_l" joint2="finger_r" polycoef="0 1 0 0 0" solref="0.01 1"/></equality>
  <actuator>
    <position name="x" joint="ee_x" kp="{kp:.6g}" dampratio="{zeta:.6g}" ctrlrange="{_f(*e.workspace_x_m)}" forcerange="{_f(-f, f)}"/>
    <position name="y" joint="ee_y" kp="{kp:.6g}" dampratio="{zeta:.6g}" ctrlrange="{_f(*e.workspace_y_m)}" forcerange="{_f(-f, f)}"/>
    <position name="z" joint="ee_z" kp="{kp:.6g}" dampratio="{zeta:.6g}" ctrlrange="{_f(*e.workspace_z_m)}" forcerange="{_f(-f, f)}"/>
    <position name="yaw" joint="ee_yaw" kp="{e.yaw_kp_nm_per_rad:.6g}" dampratio="{zeta:.6g}" ctrlrange="{yr}" forcerange="{_f(-e.yaw_torque_limit_nm, e.yaw_torque_limit_nm)}"/>
    <position name="grip" tendon="grip" kp="{e.grip_kp_n_per_m:.6g}" dampratio="{zeta:.6g}" ctrlrange="0 {e.max_opening_m:.6g}" forcerange="{_f(-e.grip_force_n, e.grip_force_n)}"/>
  </actuator>"""
    return body, act


def build_mjcf(cfg: ContactConfig, geometry: dict[str, Geometry], physics: dict[str, Physics],
               start: dict[str, Placement], fixtures: dict[str, Fixture], markers: dict[str, Marker],
               timestep: float) -> str:
    """The world's MJCF. `physics` is the truth (evaluation world) or the beliefs (planning world)."""
    t, s, cam = cfg.table, cfg.sim, cfg.camera
    table_hx = (t.edge_x_m - t.back_x_m) / 2
    bodies = "\n    ".join(_object_body(n, geometry[n], physics[n], start[n]) for n in geometry)
    fix = "\n    ".join(f'<geom name="{n}" type="box" size="{_f(*f.half)}" pos="{_f(*f.pos)}" rgba="{_f(*f.rgba)}"/>'
                        for n, f in fixtures.items())
    marks = "\n    ".join(f'<geom name="{n}" type="cylinder" size="{_f(m.radius, 0.0005)}" pos="{_f(m.x, m.y, 0.0005)}" '
                          f'rgba="{_f(*m.rgba)}" contype="0" conaffinity="0"/>' for n, m in markers.items())
    sensors = "\n    ".join(
        f'<framepos name="{n}_pos" objtype="xbody" objname="{n}"/><framequat name="{n}_quat" objtype="xbody" objname="{n}"/>'
        f'<framelinvel name="{n}_vel" objtype="xbody" objname="{n}"/>' for n in geometry)
    effector, actuators = _effector(cfg)
    fwd = [c - p for c, p in zip(cam.look_at_m, cam.pos_m)]
    right = _unit((fwd[1], -fwd[0], 0.0))
    up = _unit(_cross(right, _unit(fwd)))
    return f"""
<mujoco model="contact">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{timestep:.6g}" integrator="implicitfast" cone="elliptic" impratio="{s.impratio:.6g}"/>
  <size memory="4M"/>
  <visual>
    <quality offsamples="4" shadowsize="1024"/>
    <global offwidth="{cam.width}" offheight="{cam.height}"/>
    <headlight ambient="0.4 0.4 0.4" diffuse="0.5 0.5 0.5" specular="0.05 0.05 0.05"/>
  </visual>
  <default>
    <geom solref="{s.contact_timeconst_s:.6g} 1" solimp="0.95 0.99 0.001" condim="3"/>
  </default>
  <worldbody>
    <light pos="0.2 -0.3 1.2" dir="-0.1 0.2 -1" diffuse="0.5 0.5 0.5"/>
    <camera name="scene" pos="{_f(*cam.pos_m)}" xyaxes="{_f(*right, *up)}" fovy="{cam.fovy_deg:.6g}"/>
    <geom name="floor" type="plane" size="2 2 0.1" pos="0 0 -0.75" rgba="0.3 0.3 0.32 1"/>
    <geom name="table" type="box" size="{_f(table_hx, t.half_y_m, 0.02)}" pos="{_f(t.back_x_m + table_hx, 0, -0.02)}"
          friction="{t.friction:.6g} 0.005 0.0001" rgba="0.82 0.82 0.78 1"/>
    {fix}
    {marks}
    {bodies}
    {effector}
  </worldbody>
  {actuators}
  <sensor>
    <force name="ft_force" site="ft"/><torque name="ft_torque" site="ft"/>
    <touch name="touch_l" site="pad_l"/><touch name="touch_r" site="pad_r"/>
    <framepos name="tcp_pos" objtype="site" objname="tcp"/>
    {sensors}
  </sensor>
</mujoco>
"""


def _unit(v: tuple[float, ...] | list[float]) -> tuple[float, ...]:
    n = math.sqrt(sum(x * x for x in v)) or 1.0
    return tuple(x / n for x in v)


def _cross(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float]:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
