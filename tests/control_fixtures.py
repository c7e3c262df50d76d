"""A tiny contact scene for the task-free controller: a force-limited planar pusher and a box.

The pusher is a sphere on two slide joints (x, y) driven by position actuators with a force
range; the box is a free body on a low-friction table, so contacts with it use the box's
friction (MuJoCo takes the larger of a pair). Used by the controller's tests (bench/bench_sandbox.py
carries its own copy of the scene).
"""

from __future__ import annotations

import mujoco

TABLE_FRICTION = 0.1
BOX_HALF = (0.05, 0.05, 0.025)  # flat, so a push at mid-height cannot tip it
PUSHER_RADIUS = 0.025


def pusher_box_xml(
    *,
    box_mass: float = 0.5,
    box_friction: float = 0.5,
    box_x: float = 0.1,
    timestep: float = 0.01,
    force_limit: float = 15.0,
    kp: float = 400.0,
) -> str:
    kv = 2.0 * (kp * 1.0) ** 0.5  # critically damped for the 1 kg pusher
    return f"""
<mujoco model="pusher_box">
  <option timestep="{timestep}" cone="elliptic" impratio="3"/>
  <worldbody>
    <geom name="table" type="plane" size="2 2 0.1" friction="{TABLE_FRICTION} 0.005 0.0001"/>
    <body name="pusher" pos="0 0 {BOX_HALF[2]}">
      <joint name="px" type="slide" axis="1 0 0" damping="1"/>
      <joint name="py" type="slide" axis="0 1 0" damping="1"/>
      <geom name="pusher" type="sphere" size="{PUSHER_RADIUS}" mass="1" friction="{TABLE_FRICTION} 0.005 0.0001"
            contype="1" conaffinity="1"/>
      <site name="tip"/>
    </body>
    <body name="box" pos="{box_x} 0 {BOX_HALF[2]}">
      <freejoint name="box"/>
      <geom name="box" type="box" size="{BOX_HALF[0]} {BOX_HALF[1]} {BOX_HALF[2]}" mass="{box_mass}"
            friction="{box_friction} 0.005 0.0001"/>
    </body>
  </worldbody>
  <actuator>
    <position name="ax" joint="px" kp="{kp}" kv="{kv}" ctrlrange="-0.5 0.5" forcerange="-{force_limit} {force_limit}"/>
    <position name="ay" joint="py" kp="{kp}" kv="{kv}" ctrlrange="-0.5 0.5" forcerange="-{force_limit} {force_limit}"/>
  </actuator>
  <sensor>
    <framepos name="box_pos" objtype="body" objname="box"/>
    <framepos name="tip_pos" objtype="site" objname="tip"/>
    <actuatorfrc name="fx" actuator="ax"/>
    <actuatorfrc name="fy" actuator="ay"/>
  </sensor>
</mujoco>
"""


def pusher_box(**kw) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_string(pusher_box_xml(**kw))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data
