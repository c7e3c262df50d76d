"""The objects on the table: MJCF free bodies with typed geoms, and their known shapes.

Each object is one free body named after its kind (`bottle`, `cup`, ...), its origin at
the centre of its bounding shape, resting on the table. `SHAPES` gives the primitive a
perception module may fit (a cylinder of known radius, a box of known half-extents) and
how the `grasp` action takes the object (side-on when upright, else top-down).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from kintsugi.core.errors import ConfigError
from kintsugi.perception.features import Primitive
from kintsugi.worlds.tabletop.arm_model import f
from kintsugi.worlds.tabletop.config import ObjectSection, ObjectsSection

CUP_SEGMENTS = 12
CAPSULE_SLICES = 3
TRAY_WALL = 0.006
CAP_HALF_M = 0.01
"""A bottle's cap: a painted band this half-tall over its top end, so a camera can tell its top from its
bottom (a plain cylinder looks the same either way up, and a stand-up could set it down upside down)."""
CAP_RGBA = (0.9, 0.9, 0.9, 1.0)


@dataclass(frozen=True)
class Shape:
    """An object's known geometry, in its body frame (origin at the centre, z up)."""

    kind: Literal["cylinder", "box", "sphere"]
    radius: float = 0.0
    half_height: float = 0.0
    half_extents: tuple[float, float, float] = (0.0, 0.0, 0.0)
    grasp: Literal["side_if_upright", "top"] = "top"
    fit: bool = True
    """False for shapes a primitive describes badly (a fork's wide head on a narrow handle):
    perception then reports raw cloud features instead of a misfitted box."""
    wall: float | None = None
    """Open containers (cup, tray): wall and floor thickness; perception fits the solid minus its cavity."""
    cap: bool = False
    """A painted cap marks its top end (body +z): geom `<kind>_cap`, no mass, no contacts."""

    def primitive(self) -> Primitive:
        """The shape as the perception catalogue states it (what a fit may assume)."""
        if not self.fit:
            return Primitive()
        if self.kind == "cylinder":
            return Primitive.cylinder(self.radius, self.half_height, wall=self.wall)
        if self.kind == "sphere":
            return Primitive(kind="sphere", radius=self.radius)
        return Primitive.box(*self.half_extents, wall=self.wall)

    @property
    def rest_height(self) -> float:
        """Height of the body origin above the table when it stands upright."""
        if self.kind == "sphere":
            return self.radius
        return self.half_height if self.kind == "cylinder" else self.half_extents[2]


BUILT_IN = ("bottle", "cup", "plate", "capsule", "fork", "spoon", "tray", "block")
"""Objects with geometry of their own; any other object declares its `shape`."""


def section(kind: str, objects: ObjectsSection) -> ObjectSection:
    """The object's settings; ConfigError naming the objects configured when there is none."""
    o = getattr(objects, kind, None)
    if not isinstance(o, ObjectSection):
        known = ", ".join(type(objects).model_fields)
        raise ConfigError(f"no object {kind!r} is configured; objects: {known} (a task declares its own in "
                          "TaskSpec.declared)")
    return o


def declared_shape(o: ObjectSection) -> Shape:
    """The shape of an object a task declares (`ObjectSection.shape`)."""
    s = o.size_m
    if o.shape == "sphere":
        return Shape("sphere", radius=s[0], half_extents=(s[0], s[0], s[0]))
    if o.shape == "capsule":  # perception fits it as the cylinder it nearly is
        return Shape("cylinder", radius=s[0], half_height=s[1] + s[0], grasp="side_if_upright")
    if o.shape == "cylinder":
        return Shape("cylinder", radius=s[0], half_height=s[1], wall=o.wall_m,
                     grasp="top" if o.wall_m is not None or s[1] < s[0] else "side_if_upright")
    return Shape("box", half_extents=s, wall=o.wall_m)


def shape_of(kind: str, objects: ObjectsSection) -> Shape:
    o = section(kind, objects)
    if o.shape is not None:
        return declared_shape(o)
    if kind not in BUILT_IN:
        raise ConfigError(f"object {kind!r} declares no shape; give objects.{kind}.shape (box, cylinder, sphere "
                          "or capsule): only the built-in objects have geometry of their own "
                          f"({', '.join(BUILT_IN)})")
    s = o.size_m
    if kind in ("bottle", "cup"):
        return Shape("cylinder", radius=s[0], half_height=s[1], grasp="side_if_upright",
                     wall=s[2] if kind == "cup" else None, cap=kind == "bottle")
    if kind in ("plate", "capsule"):
        return Shape("cylinder", radius=s[0], half_height=s[1])
    if kind in ("fork", "spoon"):
        head = 0.03 if kind == "fork" else 0.022
        return Shape("box", half_extents=(s[0] + head, s[1] * 1.8, s[2]), fit=False)
    if kind == "tray":
        return Shape("box", half_extents=(s[0], s[1], s[2] / 2), wall=TRAY_WALL)
    return Shape("box", half_extents=s)


ROLLING = ("bottle", "cup", "capsule", "plate")
"""Round objects get condim 6 (rolling friction, taken from the table) so that, fallen, they stop;
flat-sided ones keep condim 3, which is cheaper."""


def _geoms(kind: str, o: ObjectSection) -> list[str]:
    s, rgba, m = o.size_m, f(*o.rgba), o.mass_kg
    condim = 6 if kind in ROLLING or (o.shape is not None and o.shape != "box") else 3
    common = f'rgba="{rgba}" friction="{o.friction:.6g} 0.005 0.0001" condim="{condim}"'
    if o.shape is not None:
        return _declared_geoms(kind, o, common)
    if kind == "capsule":
        # Stacked slices: a top-down pad (a vertical capsule) parallel to one cylinder's side gets
        # a single contact anywhere along it, often at opposite rims on the two sides, and the
        # squeeze then spits the light capsule out; one contact per slice keeps the pinch level.
        hs = s[1] / CAPSULE_SLICES
        return [f'<geom name="capsule_body{i}" type="cylinder" size="{f(s[0], hs)}" '
                f'pos="0 0 {-s[1] + (2 * i + 1) * hs:.6g}" mass="{m / CAPSULE_SLICES:.6g}" {common}/>'
                for i in range(CAPSULE_SLICES)]
    if kind == "bottle":  # the cap stands 0.5 mm proud of the body, so the cameras see it and not the body there
        return [f'<geom name="bottle_body" type="cylinder" size="{f(s[0], s[1])}" mass="{m:.6g}" {common}/>',
                f'<geom name="bottle_cap" type="cylinder" size="{f(s[0] + 0.0005, CAP_HALF_M)}" '
                f'pos="0 0 {s[1] + 0.0005 - CAP_HALF_M:.6g}" mass="0" contype="0" conaffinity="0" '
                f'rgba="{f(*CAP_RGBA)}"/>']
    if kind == "plate":
        return [f'<geom name="plate_body" type="cylinder" size="{f(s[0], s[1])}" mass="{m:.6g}" {common}/>']
    if kind == "cup":
        r, hh, wall = s
        floor = wall / 2  # half thickness: the floor is as thick as the wall
        out = [f'<geom name="cup_floor" type="cylinder" size="{f(r, floor)}" pos="0 0 {-hh + floor:.6g}" '
               f'mass="{0.3 * m:.6g}" {common}/>']
        wall_hh = hh - floor
        half_w = (r - wall / 2) * math.tan(math.pi / CUP_SEGMENTS) + 0.0015
        for k in range(CUP_SEGMENTS):
            a = 2 * math.pi * k / CUP_SEGMENTS
            rm = r - wall / 2
            out.append(
                f'<geom name="cup_wall{k}" type="box" size="{f(wall / 2, half_w, wall_hh)}" '
                f'pos="{f(rm * math.cos(a), rm * math.sin(a), floor)}" euler="0 0 {a:.6g}" '
                f'mass="{0.7 * m / CUP_SEGMENTS:.6g}" {common}/>')
        return out
    if kind in ("fork", "spoon"):
        hl, hw, ht = s
        head = 0.03 if kind == "fork" else 0.022
        x0 = -head  # centre the whole utensil on the body origin
        handle = (f'<geom name="{kind}_handle" type="box" size="{f(hl, hw, ht)}" pos="{f(x0, 0, 0)}" '
                  f'mass="{0.6 * m:.6g}" {common}/>')
        if kind == "fork":
            tip = (f'<geom name="fork_head" type="box" size="{f(head, hw * 1.8, ht)}" pos="{f(x0 + hl + head, 0, 0)}" '
                   f'mass="{0.4 * m:.6g}" {common}/>')
        else:
            tip = (f'<geom name="spoon_head" type="cylinder" size="{f(head, ht)}" pos="{f(x0 + hl + head, 0, 0)}" '
                   f'mass="{0.4 * m:.6g}" {common}/>')
        return [handle, tip]
    if kind == "tray":
        hx, hy, rim = s
        base_t = t = TRAY_WALL / 2
        z0 = -rim / 2
        out = [f'<geom name="tray_base" type="box" size="{f(hx, hy, base_t)}" pos="0 0 {z0 + base_t:.6g}" '
               f'mass="{0.6 * m:.6g}" {common}/>']
        wall = (rim - 2 * base_t) / 2  # rims stand on the base, clear of the table (fewer contacts)
        rz = z0 + 2 * base_t + wall
        for name, size, pos in (
            ("front", (t, hy, wall), (hx - t, 0, rz)), ("back", (t, hy, wall), (-hx + t, 0, rz)),
            ("left", (hx, t, wall), (0, hy - t, rz)), ("right", (hx, t, wall), (0, -hy + t, rz)),
        ):
            out.append(f'<geom name="tray_rim_{name}" type="box" size="{f(*size)}" pos="{f(*pos)}" '
                       f'mass="{0.1 * m:.6g}" {common}/>')
        return out
    return [f'<geom name="{kind}_body" type="box" size="{f(*s)}" mass="{m:.6g}" {common}/>']


def _declared_geoms(name: str, o: ObjectSection, common: str) -> list[str]:
    """One primitive geom; an open container (`wall_m`): a floor and walls (a box's four, a cylinder's ring of
    segments), the floor as thick as the walls."""
    s, m, w = o.size_m, o.mass_kg, o.wall_m
    if w is None:
        size = {"box": f(*s), "cylinder": f(s[0], s[1]), "sphere": f(s[0]), "capsule": f(s[0], s[1])}[o.shape]
        return [f'<geom name="{name}_body" type="{o.shape}" size="{size}" mass="{m:.6g}" {common}/>']
    if o.shape == "box":
        hx, hy, hz = s
        out = [f'<geom name="{name}_floor" type="box" size="{f(hx, hy, w / 2)}" pos="0 0 {-hz + w / 2:.6g}" '
               f'mass="{0.4 * m:.6g}" {common}/>']
        wz, z = hz - w / 2, w / 2
        for side, size, pos in (("front", (w / 2, hy, wz), (hx - w / 2, 0, z)), ("back", (w / 2, hy, wz), (-hx + w / 2, 0, z)),
                                ("left", (hx, w / 2, wz), (0, hy - w / 2, z)), ("right", (hx, w / 2, wz), (0, -hy + w / 2, z))):
            out.append(f'<geom name="{name}_wall_{side}" type="box" size="{f(*size)}" pos="{f(*pos)}" '
                       f'mass="{0.15 * m:.6g}" {common}/>')
        return out
    r, hh = s[0], s[1]
    out = [f'<geom name="{name}_floor" type="cylinder" size="{f(r, w / 2)}" pos="0 0 {-hh + w / 2:.6g}" '
           f'mass="{0.3 * m:.6g}" {common}/>']
    rm = r - w / 2
    half_w = rm * math.tan(math.pi / CUP_SEGMENTS) + 0.0015
    for k in range(CUP_SEGMENTS):
        a = 2 * math.pi * k / CUP_SEGMENTS
        out.append(f'<geom name="{name}_wall{k}" type="box" size="{f(w / 2, half_w, hh - w / 2)}" '
                   f'pos="{f(rm * math.cos(a), rm * math.sin(a), w / 2)}" euler="0 0 {a:.6g}" '
                   f'mass="{0.7 * m / CUP_SEGMENTS:.6g}" {common}/>')
    return out


def object_xml(kind: str, objects: ObjectsSection, extra: str = "") -> str:
    """A free body resting upright at the origin of the table; the world sets its start pose.
    `extra`: more geoms riding with it (regions painted beside it)."""
    o = section(kind, objects)
    shape = shape_of(kind, objects)
    sites = ""
    if kind == "bottle":
        sites = f'<site name="bottle_mouth" pos="0 0 {shape.half_height:.6g}" size="0.005" group="4"/>'
    geoms = "\n        ".join(_geoms(kind, o))
    return f"""
    <body name="{kind}" pos="0 0 {shape.rest_height:.6g}">
      <freejoint name="{kind}"/>
      {geoms}
      {sites}
      {extra}
    </body>"""
