"""MJCF of one 6-DoF arm with its parallel-jaw gripper, generated from the typed config.

The same builder makes the arm inside the full scene (actuated, gravity-compensated,
with a tendon-driven gripper) and the separate kinematic model the IK solves on
(joints and the tool centre point only). Joint axes: yaw, pitch, pitch, roll, pitch,
roll. At zero angles the arm points straight up; positive pitch leans it towards +x.
The gripper frame (site `<arm>_tcp`): z = approach, y = the fingers' closing axis.
"""

from __future__ import annotations

import math

from kintsugi.worlds.tabletop.config import RobotSection

JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
PAD_HALF = (0.012, 0.004, 0.025)
"""Finger pad half-extents: across the finger, thickness, along the approach axis.

The pad collides as a capsule along the approach axis (radius = the pad's half thickness):
a box face parallel to a bottle's side makes MuJoCo's convex collider flicker between
contacts and none, and the bottle creeps out of the grasp; a capsule across the bottle's
axis gives one steady point contact per finger (0.2 mm slip over a lift, tested)."""
FINGER_HALF_TRAVEL = 0.05
LINK_RGBA = "0.82 0.83 0.86 1"
HAND_RGBA = "0.2 0.2 0.22 1"


def f(*xs: float) -> str:
    return " ".join(f"{x:.6g}" for x in xs)


def base_position(robot: RobotSection, arm: str) -> tuple[float, float, float]:
    side = 1.0 if arm == "left" else -1.0
    return (robot.base_x_m, side * robot.base_spacing_m / 2, 0.0)


def arm_xml(robot: RobotSection, arm: str, kinematic: bool = False) -> str:
    """The arm's body tree (a `<body>` element for the worldbody)."""
    p = f"{arm}_"
    lim = [tuple(math.radians(v) for v in pair) for pair in robot.joint_limits_deg]
    m = robot.link_masses_kg
    gc = "" if kinematic else ' gravcomp="1"'

    def joint(i: int, axis: str) -> str:
        lo, hi = lim[i]
        return (f'<joint name="{p}{JOINTS[i]}" axis="{axis}" range="{f(lo, hi)}" '
                f'armature="{robot.armature[i]:.6g}" damping="1"/>')

    def link(fromto: tuple[float, ...], radius: float, mass: float, name: str) -> str:
        return (f'<geom name="{p}{name}" class="link" type="capsule" fromto="{f(*fromto)}" size="{radius:.6g}" '
                f'mass="{mass:.6g}"/>')

    h, l2, l3, w = robot.shoulder_height_m, robot.upper_arm_m, robot.forearm_m, robot.wrist_m
    gripper = _kinematic_hand(robot, p) if kinematic else _gripper_xml(robot, p, m[5])
    return f"""
    <body name="{p}base" pos="{f(*base_position(robot, arm))}">
      <geom name="{p}pedestal" class="link" type="cylinder" size="0.07 0.03" pos="0 0 0.03" mass="5"/>
      <body name="{p}link1"{gc}>
        {joint(0, "0 0 1")}
        {link((0, 0, 0.07, 0, 0, h), 0.05, m[0], "link1")}
        <body name="{p}link2" pos="0 0 {h:.6g}"{gc}>
          {joint(1, "0 1 0")}
          {link((0, 0, 0, 0, 0, l2), 0.045, m[1], "link2")}
          <body name="{p}link3" pos="0 0 {l2:.6g}"{gc}>
            {joint(2, "0 1 0")}
            {link((0, 0, 0, 0, 0, l3 / 2), 0.04, m[2], "link3")}
            <body name="{p}link4" pos="0 0 {l3 / 2:.6g}"{gc}>
              {joint(3, "0 0 1")}
              {link((0, 0, 0, 0, 0, l3 / 2), 0.035, m[3], "link4")}
              <body name="{p}link5" pos="0 0 {l3 / 2:.6g}"{gc}>
                {joint(4, "0 1 0")}
                {link((0, 0, 0, 0, 0, w), 0.035, m[4], "link5")}
                <body name="{p}hand" pos="0 0 {w:.6g}"{gc}>
                  {joint(5, "0 0 1")}
                  {gripper}
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>"""


def _kinematic_hand(robot: RobotSection, p: str) -> str:
    return (f'<geom type="sphere" size="0.01" mass="0.1" contype="0" conaffinity="0"/>'
            f'<site name="{p}tcp" pos="0 0 {robot.flange_to_grasp_m:.6g}"/>')


def _pad_xml(robot: RobotSection, p: str, name: str, y: float, z: float) -> str:
    """The pad's collision geom centred at (0, y, z) in the finger: a capsule along the approach
    axis (default; steady point contacts on round objects) or the full box (`robot.pad_shape`,
    a flat jaw that sweeps a cloth corner into a ridge)."""
    if robot.pad_shape == "box":
        return (f'<geom name="{p}pad_{name}" class="pad" type="box" size="{f(*PAD_HALF)}" pos="0 {y:.6g} {z:.6g}" '
                f'mass="0.05"/>')
    return (f'<geom name="{p}pad_{name}" class="pad" type="capsule" size="{PAD_HALF[1]:.6g}" '
            f'fromto="0 {y:.6g} {z - PAD_HALF[2] + PAD_HALF[1]:.6g} 0 {y:.6g} {z + PAD_HALF[2] - PAD_HALF[1]:.6g}" '
            f'mass="0.05"/>')


def _gripper_xml(robot: RobotSection, p: str, hand_mass: float) -> str:
    tcp = robot.flange_to_grasp_m
    half_open = robot.gripper_max_opening_m / 2
    finger_z = tcp - PAD_HALF[2] - 0.01  # finger body origin, just below the palm
    palm_half_y = half_open + 2 * PAD_HALF[1] + 0.006
    fingers = []
    for name, sign in (("l", 1.0), ("r", -1.0)):
        y = sign * (half_open + PAD_HALF[1])
        fingers.append(f"""
                  <body name="{p}finger_{name}" pos="0 0 {finger_z:.6g}" gravcomp="1">
                    <joint name="{p}finger_{name}" type="slide" axis="0 {-sign:g} 0" range="0 {half_open:.6g}"
                           damping="40" armature="0.01"/>
                    {_pad_xml(robot, p, name, y, tcp - finger_z)}
                    <geom class="visual" type="box" size="{f(*PAD_HALF)}" pos="0 {y:.6g} {tcp - finger_z:.6g}"/>
                    <geom class="visual" type="box" size="{f(PAD_HALF[0], PAD_HALF[1], 0.012)}" pos="0 {y:.6g} 0.012"/>
                  </body>""")
    palm_half_z = (finger_z) / 2
    return f"""<geom name="{p}palm" class="link" type="box" size="{f(0.03, palm_half_y, palm_half_z)}"
                        pos="0 0 {palm_half_z:.6g}" mass="{hand_mass:.6g}" rgba="{HAND_RGBA}"/>
                  <site name="{p}tcp" pos="0 0 {tcp:.6g}" size="0.004" rgba="1 0 0 0.5" group="4"/>{"".join(fingers)}"""


def arm_actuators_xml(robot: RobotSection, arm: str) -> str:
    """Torque-limited joint position servos and the force-limited gripper tendon servo."""
    p = f"{arm}_"
    out = []
    for i, j in enumerate(JOINTS):
        lo, hi = (math.radians(v) for v in robot.joint_limits_deg[i])
        t = robot.torque_limits_nm[i]
        out.append(f'<position name="{p}{j}" joint="{p}{j}" kp="{robot.kp[i]:.6g}" dampratio="1" '
                   f'ctrlrange="{f(lo, hi)}" forcerange="{f(-t, t)}"/>')
    g = robot.grip_force_n
    g_open = g if robot.gripper_open_force_n is None else robot.gripper_open_force_n
    out.append(f'<position name="{p}grip" tendon="{p}grip" kp="{robot.gripper_kp:.6g}" '
               f'ctrlrange="0 {robot.gripper_max_opening_m:.6g}" forcerange="{f(-g_open, g)}"/>')
    return "\n    ".join(out)


def arm_tendon_xml(arm: str) -> str:
    """Grip tendon = total closing travel of both fingers (0 = fully open)."""
    p = f"{arm}_"
    return (f'<fixed name="{p}grip"><joint joint="{p}finger_l" coef="1"/><joint joint="{p}finger_r" coef="1"/>'
            f'</fixed>')


def arm_equality_xml(arm: str) -> str:
    """The fingers move together (a parallel-jaw linkage)."""
    p = f"{arm}_"
    return f'<joint joint1="{p}finger_l" joint2="{p}finger_r" polycoef="0 1 0 0 0" solref="0.004 1"/>'


def kinematic_xml(robot: RobotSection, arm: str) -> str:
    """One arm alone, no actuators, no gripper, no objects: the model IK solves on."""
    return f"""
<mujoco model="{arm}_arm_kinematics">
  <compiler angle="radian" autolimits="true"/>
  <default><geom contype="0" conaffinity="0"/><default class="link"/></default>
  <worldbody>{arm_xml(robot, arm, kinematic=True)}
  </worldbody>
</mujoco>"""
