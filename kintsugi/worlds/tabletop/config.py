"""Every parameter of the bimanual tabletop world, typed; `--set robot.grip_force_n=5` overrides.

Units: metres, kilograms, newtons, seconds; angles in degrees (as a user types them).
World frame: the table top is the plane z = 0, the robot stands at the back edge
(x < 0) and faces +x; its left arm is at +y, its right arm at -y.
"""

from __future__ import annotations

import re
from typing import Literal

from pydantic import Field, field_validator, model_validator

from kintsugi.core.config import Range, SimSection as BaseSim, StrictModel

Vec3 = tuple[float, float, float]
SixFloats = tuple[float, float, float, float, float, float]


class RobotSection(StrictModel):
    """Two identical 6-DoF arms (yaw, pitch, pitch, roll, pitch, roll), parallel-jaw grippers."""

    base_spacing_m: float = Field(0.6, gt=0.2, le=1.5)
    """Distance between the two arm bases along y."""
    base_x_m: float = -0.05
    shoulder_height_m: float = Field(0.12, gt=0.02)
    upper_arm_m: float = Field(0.40, gt=0.1)
    forearm_m: float = Field(0.35, gt=0.1)
    wrist_m: float = Field(0.06, gt=0.01)
    """Wrist pitch axis to the flange."""
    link_masses_kg: SixFloats = (2.0, 2.5, 1.6, 0.6, 0.5, 0.3)
    joint_limits_deg: tuple[tuple[float, float], ...] = (
        (-165, 165), (-90, 120), (-15, 165), (-170, 170), (-125, 125), (-175, 175))
    kp: SixFloats = (2500, 2500, 1800, 500, 500, 300)
    """Position-actuator stiffness per joint (N m / rad); damping is set for a damping ratio of 1."""
    torque_limits_nm: SixFloats = (150, 150, 100, 28, 28, 28)
    armature: SixFloats = (0.2, 0.2, 0.1, 0.03, 0.03, 0.02)
    """Reflected rotor inertia per joint (kg m^2)."""
    home_deg: SixFloats = (0.0, -20.0, 110.0, 0.0, 90.0, 0.0)
    """The `back` configuration: gripper pointing down, 0.35 m above the table, clear of the objects."""
    gripper_max_opening_m: float = Field(0.10, gt=0.02, le=0.2)
    grip_force_n: float = Field(20.0, gt=0)
    """Squeeze of each finger when closed (the tendon actuator's force limit)."""
    gripper_kp: float = Field(800.0, gt=0)
    pad_friction: float = Field(1.5, gt=0)
    pad_torsional_m: float = Field(0.01, ge=0)
    """Torsional friction of the finger pads (condim 4), as a length."""
    flange_to_grasp_m: float = Field(0.085, gt=0.03)
    """Flange to the grasp point between the finger pads (the tool centre point)."""
    gripper_open_force_n: float | None = Field(None, gt=0)
    """Force limit of the opening stroke; None: the same as grip_force_n. A weak opening lets a
    pinched cloth go without flinging it."""
    pad_shape: Literal["capsule", "box"] = "capsule"
    """Collision shape of the finger pads: a capsule along the approach axis (rigid objects), or the
    pad's full box (a flat jaw, for pinching cloth)."""

    @model_validator(mode="after")
    def _six_joints(self) -> RobotSection:
        if len(self.joint_limits_deg) != 6:
            raise ValueError("robot.joint_limits_deg needs 6 [low, high] pairs")
        for (lo, hi), h in zip(self.joint_limits_deg, self.home_deg):
            if lo >= hi:
                raise ValueError(f"robot.joint_limits_deg pair [{lo}, {hi}] has low >= high")
            if not lo <= h <= hi:
                raise ValueError(f"robot.home_deg {h} is outside its joint limit [{lo}, {hi}]")
        return self


Primitive = Literal["box", "cylinder", "sphere", "capsule"]
COLOURS: dict[str, tuple[float, float, float, float]] = {
    "red": (0.85, 0.2, 0.2, 1.0), "green": (0.25, 0.7, 0.3, 1.0), "blue": (0.2, 0.35, 0.85, 1.0),
    "yellow": (0.9, 0.8, 0.2, 1.0), "orange": (0.95, 0.55, 0.15, 1.0), "purple": (0.55, 0.3, 0.75, 1.0),
    "white": (0.92, 0.92, 0.9, 1.0), "black": (0.12, 0.12, 0.12, 1.0), "grey": (0.6, 0.6, 0.6, 1.0),
    "brown": (0.5, 0.33, 0.2, 1.0)}
"""Colour names a task may give an object (its `colour`), as the instruction names them ("the red block")."""


class ObjectSection(StrictModel):
    """One object: its shape, size, mass, friction, colour and where it may start.

    The built-in objects (bottle, cup, plate, ...) have geometry of their own and leave `shape` unset. An
    object a task declares gives `shape`, one primitive: `box` (size: half-extents x, y, z), `cylinder`
    (radius, half-height, -), `sphere` (radius, -, -) or `capsule` (radius, half-length of its straight part,
    -), lying with its axis vertical; `wall_m` makes a box or cylinder an open container (a bin, a bowl) with
    walls and floor this thick."""

    size_m: Vec3
    """Built-in cylinder-like: (radius, half-height, wall); box-like: half-extents (x, y, z); see above."""
    mass_kg: float = Field(gt=0)
    friction: float = Field(0.8, gt=0)
    rgba: tuple[float, float, float, float] = (0.6, 0.6, 0.6, 1.0)
    x_m: Range
    y_m: Range
    yaw_deg: Range = (0.0, 0.0)
    """Start pose ranges; the `none` condition uses each range's midpoint."""
    shape: Primitive | None = None
    """The primitive of an object a task declares; None: a built-in object's own geometry."""
    kind: str | None = Field(None, pattern=r"^[a-z][a-z_]*$")
    """What it is, as an instruction names it ("block", "ball", "bowl"); None: its name."""
    colour: str | None = None
    """A colour name from `COLOURS` (sets `rgba`), as an instruction names it; None: `rgba` as given."""
    wall_m: float | None = Field(None, gt=0.0, le=0.05)

    @model_validator(mode="after")
    def _declared(self) -> "ObjectSection":
        if self.colour is not None:
            if self.colour not in COLOURS:
                raise ValueError(f"colour {self.colour!r} is not one of {', '.join(COLOURS)}")
            object.__setattr__(self, "rgba", COLOURS[self.colour])
        if self.shape is None and (self.wall_m is not None):
            raise ValueError("wall_m needs a declared shape (box or cylinder)")
        if self.wall_m is not None and self.shape not in ("box", "cylinder"):
            raise ValueError(f"wall_m (an open container) needs a box or cylinder, not a {self.shape}")
        if min(self.size_m[:1]) <= 0 or (self.shape == "box" and min(self.size_m) <= 0) or (
                self.shape in ("cylinder", "capsule") and self.size_m[1] <= 0):
            raise ValueError(f"size_m {self.size_m} has a non-positive dimension this shape needs")
        return self


def _obj(size, mass, friction, rgba, x, y, yaw=(0.0, 0.0)) -> ObjectSection:  # noqa: ANN001
    return ObjectSection(size_m=size, mass_kg=mass, friction=friction, rgba=rgba, x_m=x, y_m=y, yaw_deg=yaw)


class ObjectsSection(StrictModel):
    bottle: ObjectSection = _obj((0.03, 0.10, 0.0), 0.40, 0.8, (0.15, 0.45, 0.9, 1), (0.35, 0.43), (-0.30, -0.22))
    cup: ObjectSection = _obj((0.045, 0.045, 0.005), 0.15, 0.8, (0.9, 0.75, 0.2, 1), (0.42, 0.50), (-0.06, 0.04))
    """Hollow: (outer radius, half-height, wall thickness)."""
    plate: ObjectSection = _obj((0.10, 0.008, 0.0), 0.30, 0.6, (0.92, 0.92, 0.88, 1), (0.50, 0.56), (-0.03, 0.03))
    fork: ObjectSection = _obj((0.09, 0.009, 0.006), 0.05, 0.8, (0.7, 0.7, 0.75, 1), (0.26, 0.34), (0.22, 0.28),
                               (75.0, 105.0))
    """Handle half-length, handle half-width, half-thickness (the head is wider). At yaw 0 the head points +x."""
    spoon: ObjectSection = _obj((0.09, 0.009, 0.006), 0.05, 0.8, (0.75, 0.7, 0.7, 1), (0.26, 0.34), (-0.28, -0.22),
                                (-105.0, -75.0))
    """Mirrors the fork: its head points outwards (-y), so the right arm turns it as the left turns the fork."""
    block: ObjectSection = _obj((0.025, 0.025, 0.025), 0.10, 0.8, (0.85, 0.2, 0.2, 1), (0.35, 0.45), (0.15, 0.25),
                                (-20.0, 20.0))
    capsule: ObjectSection = _obj((0.018, 0.015, 0.0), 0.015, 0.8, (0.55, 0.3, 0.1, 1), (0.35, 0.42), (0.18, 0.25))
    tray: ObjectSection = _obj((0.11, 0.08, 0.02), 0.30, 0.6, (0.35, 0.25, 0.2, 1), (0.38, 0.42), (-0.05, 0.05))
    """Base half-extents x, y and rim height."""


OBJECT_KINDS = tuple(ObjectsSection.model_fields)
"""The built-in objects; a task declares more of its own (`TaskSpec.declared`)."""


class Region(StrictModel):
    """A target region painted on the table (visual only): centre and half-extents (x, y).

    With `relative_to` the centre is an offset from that object's centre and the region moves
    with it ("beside the plate"); else it is fixed on the table."""

    center_m: tuple[float, float]
    half_m: tuple[float, float] = Field((0.04, 0.04), description="half-extents along x and y")
    relative_to: str | None = None

    @field_validator("half_m")
    @classmethod
    def _positive(cls, v: tuple[float, float]) -> tuple[float, float]:
        if min(v) <= 0:
            raise ValueError(f"half-extents {v} must be positive")
        return v

    @field_validator("relative_to")
    @classmethod
    def _an_object(cls, v: str | None) -> str | None:
        if v is not None and not re.fullmatch(r"[a-z][a-z0-9_]*", v):
            raise ValueError(f"{v!r} is not an object name")
        return v


class TableSection(StrictModel):
    half_m: tuple[float, float] = (0.5, 0.75)
    center_x_m: float = 0.3
    friction: float = Field(0.8, gt=0)
    rolling_friction: float = Field(0.002, ge=0)
    """condim 6 rolling friction (as a length) so that a fallen bottle stops rolling."""


class SimSection(BaseSim):
    timestep_s: float = Field(0.002, gt=0, le=0.005)
    impratio: float = Field(10.0, ge=1)
    iterations: int = Field(30, ge=1)
    contact_timeconst_s: float = Field(0.004, gt=0)
    """Contact stiffness (solref); keep it >= 2 x timestep."""
    contact_width_m: float = Field(0.01, gt=0)
    """Penetration over which a contact's impedance rises from 0.95 to 0.99 (solimp width). At
    1 mm, a block or tray that lands on a corner at 2 m/s sinks 5 mm in one step, meets the
    stiffest impedance at once and leaves with more energy than it fell with (up to 40x);
    at 1 cm no drop gains energy (tests/worlds/tabletop/test_tabletop_physics.py)."""
    control_dt_s: float = Field(0.01, gt=0)
    """How often a motion updates joint targets and watchers run."""

class MotionSection(StrictModel):
    joint_speed_deg_s: float = Field(90.0, gt=0)
    """Peak joint speed of the interpolated joint-space moves."""
    linear_speed_m_s: float = Field(0.15, gt=0)
    """Tool speed of straight-line moves (grasp approach, lift, place, retreat)."""
    rotate_speed_deg_s: float = Field(120.0, gt=0)
    settle_tol_deg: float = Field(0.3, gt=0)
    settle_timeout_s: float = Field(1.0, ge=0)
    gripper_time_s: float = Field(0.4, gt=0)
    reach_tol_m: float = Field(0.01, gt=0)
    reach_tol_deg: float = Field(5.0, gt=0)
    """An action reached its target when every move settled this close to its pose."""
    ik_pos_tol_m: float = Field(0.001, gt=0)
    ik_rot_tol_deg: float = Field(1.0, gt=0)
    ik_max_iters: int = Field(60, ge=1)
    workspace_x_m: Range = (0.05, 0.75)
    workspace_y_m: Range = (-0.65, 0.65)
    workspace_z_m: Range = (0.005, 0.6)
    """Targets of the tool centre point are clipped to this box before IK (as in the paper)."""
    retreat_m: float = Field(0.08, gt=0)
    """How far `place` backs the open gripper away along its approach axis."""


class CameraSection(StrictModel):
    width: int = Field(320, ge=64, le=2048)
    height: int = Field(240, ge=48, le=2048)
    top_height_m: float = Field(1.3, gt=0.3)
    top_fovy_deg: float = Field(58.0, gt=5, lt=170)
    front_pos_m: Vec3 = (1.45, 0.0, 0.85)
    front_look_at_m: Vec3 = (0.3, 0.0, 0.18)
    front_fovy_deg: float = Field(48.0, gt=5, lt=170)


class DisturbanceSection(StrictModel):
    drop_p: float = Field(0.05, ge=0, le=1)
    """Probability, per atomic action, that a held object is released at a random instant of it."""
    drop_release_s: float = Field(0.3, gt=0)
    """How long the gripper is forced open to let the object go."""
    shift_m: Range = (0.03, 0.06)
    """`shift`: how far the task's target object is slid across the table."""
    shift_duration_s: float = Field(0.4, gt=0)
    knock_push: float = Field(1.0, gt=0, le=20)
    """`knock`: horizontal push at the object's top, in units of its weight."""
    knock_duration_s: float = Field(0.15, gt=0, le=2)


class PerceptionSection(StrictModel):
    objects: Literal["perceived", "truth"] = "perceived"
    """Object features from seg+depth renders (default) or from ground-truth poses (the paper's simulation)."""


class ScoringSection(StrictModel):
    pour_tilt_deg: float = Field(80.0, gt=0, le=180)
    """The designated pouring orientation: the bottle's axis at least this far from vertical."""
    upright_tol_deg: float = Field(10.0, gt=0)
    align_tol_deg: float = Field(15.0, gt=0, le=180)
    """A placed utensil's head may point this far from its required direction."""
    rest_speed_m_s: float = Field(0.02, gt=0)


class TabletopConfig(StrictModel):
    robot: RobotSection = RobotSection()
    objects: ObjectsSection = ObjectsSection()
    targets: dict[str, Region] = {}
    """Where things must end up; a region constrains the object's centre (e.g. the tray's centre). Each task
    declares its own (`TaskSpec.regions`), which become this section's defaults in the task's config."""
    table: TableSection = TableSection()
    sim: SimSection = SimSection()
    motion: MotionSection = MotionSection()
    cameras: CameraSection = CameraSection()
    disturbance: DisturbanceSection = DisturbanceSection()
    perception: PerceptionSection = PerceptionSection()
    scoring: ScoringSection = ScoringSection()

    @model_validator(mode="after")
    def _regions_beside_objects(self) -> "TabletopConfig":
        known = type(self.objects).model_fields
        for name, r in self.targets.items():
            if r.relative_to is not None and r.relative_to not in known:
                raise ValueError(f"targets.{name}.relative_to is {r.relative_to!r}, not an object; objects: "
                                 f"{', '.join(known)}")
        return self


ARMS = ("left", "right")
