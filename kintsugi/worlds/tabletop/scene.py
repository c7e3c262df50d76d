"""The full tabletop scene as MJCF: table, two arms, the task's objects, target regions, cameras.

Only the objects a task uses are built (fewer bodies, faster steps). Contact settings
follow what holds a friction grasp through a lift and a pour in MuJoCo: elliptic cone,
impratio 10, implicitfast, finger pads with priority 1, condim 4 and friction 1.5, and
rolling friction between round objects (condim 6) and the table so that a fallen bottle stops.
The table top collides as a plane (cheaper than a box: ~20k instead of ~13k steps/s for the
full scene), so an object pushed past the edge rests at table height instead of falling.
Collision groups: arm links (contype 2) touch the table, objects and pads but never
each other; objects, pads and the table (contype 1) touch everything.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from kintsugi.worlds.tabletop.arm_model import (
    arm_actuators_xml,
    arm_equality_xml,
    arm_tendon_xml,
    arm_xml,
    f,
)
from kintsugi.worlds.tabletop.config import ARMS, TabletopConfig
from kintsugi.worlds.tabletop.objects import object_xml, shape_of

TABLE_THICK = 0.04
REGION_RGBA = "0.2 0.8 0.3 0.45"
CAMERAS = ("top", "front")


def _look_at_xyaxes(pos: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Camera x (image right) and y (image up) axes for a camera at `pos` looking at `target`."""
    back = pos - target
    back = back / np.linalg.norm(back)
    right = np.cross(np.array([0.0, 0.0, 1.0]), back)
    right = right / np.linalg.norm(right)
    return right, np.cross(back, right)


def _cameras(cfg: TabletopConfig) -> str:
    c = cfg.cameras
    x, y = _look_at_xyaxes(np.array(c.front_pos_m), np.array(c.front_look_at_m))
    return (f'<camera name="top" pos="{f(cfg.table.center_x_m, 0, c.top_height_m)}" xyaxes="0 -1 0 1 0 0" '
            f'fovy="{c.top_fovy_deg:.6g}"/>\n    '
            f'<camera name="front" pos="{f(*c.front_pos_m)}" xyaxes="{f(*x, *y)}" fovy="{c.front_fovy_deg:.6g}"/>')


def _regions(cfg: TabletopConfig, names: Sequence[str], relative_to: str | None = None, z: float = 0.0) -> str:
    """Painted regions fixed on the table, or (`relative_to`) riding in that object's body at
    height `z` below its origin. Their geoms are named `target_<name>` (perception skips them)."""
    out = []
    for name in names:
        r = cfg.targets[name]
        if r.relative_to != relative_to:
            continue
        out.append(f'<geom name="target_{name}" type="box" size="{f(*r.half_m, 0.0005)}" '
                   f'pos="{f(*r.center_m, 0.0006 - z)}" rgba="{REGION_RGBA}" contype="0" conaffinity="0" '
                   f'density="0"/>')
    return "\n    ".join(out)


@dataclass(frozen=True)
class SceneExtra:
    """What a task adds to the shared scene beyond rigid objects (e.g. a cloth): worldbody XML,
    `<option>` attributes that replace the defaults for that scene only, and the names of the
    flex objects it brings (world.pad_contacts reports them like objects)."""

    worldbody: str = ""
    option: dict[str, str] = field(default_factory=dict)
    flexes: tuple[str, ...] = ()


def _option_xml(cfg: TabletopConfig, extra: SceneExtra | None) -> str:
    s = cfg.sim
    attrs = {"timestep": f"{s.timestep_s:.6g}", "integrator": "implicitfast", "cone": "elliptic",
             "impratio": f"{s.impratio:.6g}", "solver": "Newton", "iterations": str(s.iterations),
             "ls_iterations": "20", "gravity": "0 0 -9.81"}
    attrs |= extra.option if extra is not None else {}
    return "<option " + " ".join(f'{k}="{v}"' for k, v in attrs.items()) + "/>"


def build_scene_xml(cfg: TabletopConfig, objects: Sequence[str], targets: Sequence[str] = (),
                    extra: SceneExtra | None = None) -> str:
    s, t, r = cfg.sim, cfg.table, cfg.robot
    solref = f"{s.contact_timeconst_s:.6g} 1"
    arms = "".join(arm_xml(r, arm) for arm in ARMS)
    actuators = "\n    ".join(arm_actuators_xml(r, arm) for arm in ARMS)
    tendons = "\n    ".join(arm_tendon_xml(arm) for arm in ARMS)
    equalities = "\n    ".join(arm_equality_xml(arm) for arm in ARMS)
    bodies = "".join(object_xml(kind, cfg.objects, _regions(cfg, targets, kind, shape_of(kind, cfg.objects).rest_height))
                     for kind in objects)
    return f"""
<mujoco model="tabletop">
  <compiler angle="radian" autolimits="true"/>
  {_option_xml(cfg, extra)}
  <size memory="16M"/>
  <visual>
    <quality offsamples="0" shadowsize="0"/>
    <global offwidth="{cfg.cameras.width}" offheight="{cfg.cameras.height}"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.55 0.55 0.55" specular="0 0 0"/>
    <map znear="0.05" zfar="5"/>
  </visual>
  <default>
    <geom solref="{solref}" solimp="0.95 0.99 {s.contact_width_m:.6g}" condim="3" contype="1" conaffinity="1"/>
    <default class="link"><geom contype="2" conaffinity="1" rgba="{'0.82 0.83 0.86 1'}"/></default>
    <default class="visual"><geom contype="0" conaffinity="0" density="0" rgba="0.2 0.2 0.22 1"/></default>
    <default class="pad">
      <geom priority="1" condim="4" friction="{r.pad_friction:.6g} {r.pad_torsional_m:.6g} 0.0001"
            rgba="0.15 0.15 0.15 1"/>
    </default>
  </default>
  <worldbody>
    {_cameras(cfg)}
    <geom name="table" type="plane" size="{f(*t.half_m, 0.01)}" pos="{f(t.center_x_m, 0, 0)}"
          friction="{t.friction:.6g} 0.005 {t.rolling_friction:.6g}" rgba="0.62 0.5 0.38 1"/>
    <geom name="table_body" class="visual" type="box" size="{f(*t.half_m, TABLE_THICK / 2 - 0.0005)}"
          pos="{f(t.center_x_m, 0, -TABLE_THICK / 2 - 0.0005)}" rgba="0.55 0.44 0.33 1"/>
    {_regions(cfg, targets)}
    {arms}
    {bodies}
    {extra.worldbody if extra is not None else ""}
  </worldbody>
  <tendon>
    {tendons}
  </tendon>
  <equality>
    {equalities}
  </equality>
  <actuator>
    {actuators}
  </actuator>
</mujoco>
"""
