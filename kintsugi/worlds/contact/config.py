"""Every parameter of system C's contact world, its six paper tasks and the sections a task declares, typed.

`--set box.mass_kg=[0.2,0.4]` overrides one.

Units: metres, kilograms, newtons, seconds; angles in degrees. World frame: the table top
is the plane z = 0 and its front edge is at x = `table.edge_x_m`; the end effector works
above it. Every randomized quantity is a `Range`: the `none` condition uses its midpoint,
`random` draws it uniformly (see conditions.py).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from kintsugi.core.config import Range, SimSection as BaseSim, StrictModel
from kintsugi.worlds.contact.objects import COLOURS

RGBA = tuple[float, float, float, float]


class EffectorSection(StrictModel):
    """A force-limited end effector: position actuators on x, y, z, yaw and the gripper opening.

    Each actuator is a PD servo whose force is clipped to its range, so pushing into a wall
    presses with at most `force_limit_n` (a mocap body would press with any force).
    """

    kp_n_per_m: float = Field(600.0, gt=0)
    """Stiffness of the x, y, z servos."""
    force_limit_n: float = Field(25.0, gt=0)
    """Force range of each of the x, y, z servos."""
    yaw_kp_nm_per_rad: float = Field(8.0, gt=0)
    yaw_torque_limit_nm: float = Field(1.5, gt=0)
    damping_ratio: float = Field(1.0, gt=0)
    grip_kp_n_per_m: float = Field(1500.0, gt=0)
    grip_force_n: float = Field(20.0, gt=0)
    """Squeeze of the gripper (the opening servo's force limit)."""
    max_opening_m: float = Field(0.10, gt=0.02, le=0.2)
    finger_length_m: float = Field(0.06, gt=0.02)
    finger_width_m: float = Field(0.02, gt=0.005)
    """Finger extent along the hand's x axis (across the pinch)."""
    finger_thickness_m: float = Field(0.012, gt=0.004)
    pad_friction: float = Field(1.2, gt=0)
    pad_torsion_m: float = Field(0.01, ge=0)
    """Torsional friction of the finger pads (condim 4): resists an object turning in the pinch."""
    hand_mass_kg: float = Field(0.4, gt=0)
    finger_mass_kg: float = Field(0.05, gt=0)
    armature: float = Field(0.05, ge=0)
    """Reflected inertia of each joint (kg or kg m^2)."""
    workspace_x_m: Range = (-0.30, 0.45)
    workspace_y_m: Range = (-0.28, 0.28)
    workspace_z_m: Range = (0.0, 0.30)
    """The z joint is the height of the fingertips above the table top."""
    yaw_range_deg: Range = (-100.0, 100.0)
    home_m: tuple[float, float, float] = (-0.15, 0.0, 0.15)


class TableSection(StrictModel):
    edge_x_m: float = 0.30
    """The table's front edge (+x); push-pick-board pushes the handle over it."""
    back_x_m: float = -0.40
    half_y_m: float = Field(0.35, gt=0.1)
    friction: float = Field(0.3, gt=0)
    """Used only where the other geom has no friction of its own (objects' frictions win, see scene.py)."""


class SimSection(BaseSim):
    timestep_s: float = Field(0.002, gt=0, le=0.005)
    """Evaluation world (the truth)."""
    planning_timestep_s: float = Field(0.01, gt=0, le=0.02)
    """Planning world: MPPI's rollouts step at this (coarser) timestep."""
    contact_timeconst_s: float = Field(0.02, gt=0)
    """Contact stiffness (solref) of both worlds; keep it >= 2 x planning_timestep_s."""
    impratio: float = Field(1.0, ge=1)

    def coarsest_step(self) -> tuple[str, float]:
        return "planning_timestep_s", self.planning_timestep_s


class ControlSection(StrictModel):
    """The receding-horizon loop: MPPI replans every 1 / rate_hz seconds of sim time."""

    rate_hz: float = Field(10.0, gt=0, le=100)
    samples: int = Field(256, ge=2)
    horizon_s: float = Field(0.5, gt=0)
    knots: int = Field(4, ge=1)
    noise_frac: float = Field(0.04, ge=0)
    """Noise std at the first knot as a fraction of each actuator's range (see effector.*)."""
    noise_ramp: float = Field(2.0, ge=0)
    ess_fraction: float = Field(0.1, gt=0, le=1)
    nthread: int | None = Field(None, ge=1)
    """Rollout threads; None = every core."""
    episode_s: float = Field(12.0, gt=0)
    """One attempt's sim-time budget."""
    attractor_samples: int = Field(8, ge=1)
    """Candidate contact points sampled per contact region."""


class SysIdSection(StrictModel):
    """The `mppi-sysid` method: a wrong prior, corrected after each failed attempt."""

    prior_density_kg_m3: float = Field(8000.0, gt=0)
    """The planning world starts with each object's known-model volume at this density (steel: a wrong prior for
    wood and cardboard), clipped to `mass_bounds_kg`; never the trial's truth or the middle of its ranges."""
    prior_friction: float = Field(0.9, gt=0)
    """The planning world's starting friction of every object against the table."""
    max_attempts: int = Field(4, ge=1)
    """Attempts per trial; system identification runs after each failed one (the scene is reset between)."""
    mass_bounds_kg: Range = (0.02, 5.0)
    """Where the fit searches the object's mass."""
    friction_bounds: Range = (0.05, 1.5)


class CoralSection(StrictModel):
    """The `coral` methods (CoRAL and its ablations): attempts and the retrieval memory."""

    max_attempts: int = Field(4, ge=1, le=10)
    """MPPI attempts per trial; the outer loop adapts after each failed one (the scene is reset between)."""
    memory_path: str | None = None
    """SQLite file of successful episodes, shared by a campaign's trials (run them with --workers 1, in order)."""
    memory_threshold: float = Field(0.6, ge=0, le=1)
    """A stored episode at least this similar replaces the formulation call."""
    prior_mass_scale: float = Field(1.0, gt=0, le=100)
    """Stress: the physics-priors reply's masses times this (a model that misjudges the material), before anything
    plans with them; 1 = as the model answered."""
    prior_friction_scale: float = Field(1.0, gt=0, le=100)
    """Stress: the same for the friction coefficients."""


class CameraSection(StrictModel):
    width: int = Field(480, ge=64, le=2048)
    height: int = Field(360, ge=48, le=2048)
    pos_m: tuple[float, float, float] = (0.75, -0.65, 0.55)
    look_at_m: tuple[float, float, float] = (0.05, 0.0, 0.03)
    fovy_deg: float = Field(45.0, gt=5, lt=170)


class PerceptionSection(StrictModel):
    """Where a method's object poses come from (see `kintsugi.worlds.contact.perception`)."""

    poses: Literal["perceived", "truth"] = "perceived"
    """perceived: estimated from the scene camera's depth and segmentation renders (with noise and latency);
    truth: the simulator's exact poses, an oracle. Methods with the true physics (the experts) always get truth."""
    rate_hz: float = Field(10.0, gt=0, le=100)
    latency_s: float = Field(0.05, ge=0, le=1)
    depth_noise_m: float = Field(0.001, ge=0, le=0.05)
    """Depth noise (standard deviation) at 1 m; it grows with the square of the distance."""
    width: int = Field(240, ge=32, le=2048)
    height: int = Field(180, ge=24, le=2048)
    """Size of the depth and segmentation renders (at most the scene camera's `camera.width` x `camera.height`)."""
    min_points: int = Field(30, ge=5)
    """An object with fewer pixels in view keeps its last pose."""


class BoxSection(StrictModel):
    """A box on the table: full size, mass, friction (against the table) and where it starts."""

    size_m: tuple[Range, Range, Range]
    mass_kg: Range
    friction: Range
    x_m: Range
    y_m: Range
    yaw_deg: Range = (0.0, 0.0)
    rgba: RGBA = (0.85, 0.35, 0.15, 1.0)


SHAPE_SIZES: dict[str, tuple[str, ...]] = {
    "box": ("size_x", "size_y", "size_z"),
    "cylinder": ("diameter", "length"),
    "capsule": ("diameter", "length"),
    "sphere": ("diameter",),
    "board": ("plate_x", "plate_y", "handle_x", "handle_y", "thickness"),
}
"""What `ObjectSection.size_m` lists for each shape (full sizes, metres): a box's x, y, z; a cylinder's or
capsule's diameter and length along its axis (a capsule's caps included); a sphere's diameter; a board (two
parts: a flat plate and a handle along +x) its plate's x and y, its handle's x and y and its thickness."""


class ObjectSection(StrictModel):
    """One object a task declares: shape, what it is called and looks made of, sizes, mass, friction, start.

    `label` and `material` are what the robot's scene description says of it ("red puck", "wood"): a user's
    words, never its mass or friction (those are drawn from `mass_kg` and `friction`, the hidden truth)."""

    shape: str = "box"
    """One of `SHAPE_SIZES`: box, cylinder, capsule, sphere, board."""
    label: str = ""
    """What it is called ("wooden cylinder"); empty: the section's name."""
    material: str = ""
    """What it looks made of ("wood", "steel", "foam"); empty: not said."""
    colour: str = ""
    """A colour name (`kintsugi.worlds.contact.objects.COLOURS`: red, green, blue, ...) that sets `rgba`; empty:
    `rgba` as given, no colour named."""
    size_m: tuple[Range, ...]
    """Full sizes, as `SHAPE_SIZES` lists them for the shape; each a range."""
    axis: Literal["x", "y", "z"] = "z"
    """A cylinder's or capsule's long axis: z stands it on its end, x or y lays it on its side."""
    mass_kg: Range
    friction: Range
    x_m: Range
    y_m: Range
    yaw_deg: Range = (0.0, 0.0)
    rgba: RGBA = (0.7, 0.7, 0.7, 1.0)

    @model_validator(mode="after")
    def _sizes(self) -> "ObjectSection":
        if self.shape not in SHAPE_SIZES:
            raise ValueError(f"unknown shape {self.shape!r}; known: {', '.join(SHAPE_SIZES)}")
        names = SHAPE_SIZES[self.shape]
        if self.size_m is not None and len(self.size_m) != len(names):
            raise ValueError(f"a {self.shape}'s size_m lists {len(names)} ranges ({', '.join(names)}), "
                             f"not {len(self.size_m)}")
        if self.size_m is not None and any(r[0] <= 0 for r in self.size_m):
            raise ValueError(f"size_m {self.size_m} has a non-positive size")
        if self.colour:
            if self.colour not in COLOURS:
                raise ValueError(f"unknown colour {self.colour!r}; known: {', '.join(COLOURS)}")
            object.__setattr__(self, "rgba", COLOURS[self.colour])
        return self


class FixtureSection(StrictModel):
    """A static box a task declares (a wall, a post, an obstacle): full size, where its centre stands on the table."""

    size_m: tuple[float, float, float]
    x_m: Range
    y_m: Range
    label: str = ""
    """What it is called ("grey post"); empty: the section's name."""
    rgba: RGBA = (0.45, 0.45, 0.5, 1.0)

    @model_validator(mode="after")
    def _positive(self) -> "FixtureSection":
        if min(self.size_m) <= 0:
            raise ValueError(f"size_m {self.size_m} has a non-positive size")
        return self


class MarkerSection(StrictModel):
    """A goal disc a task declares, painted on the table (no collisions)."""

    x_m: Range
    y_m: Range
    radius_m: float = Field(gt=0)
    label: str = ""
    """What it is called ("green disc"); empty: the section's name."""
    rgba: RGBA = (0.1, 0.8, 0.2, 0.45)


class BoardSection(StrictModel):
    """A cutting board: a flat plate with a handle on its +x side, lying on the table."""

    plate_m: tuple[Range, Range] = ((0.20, 0.26), (0.16, 0.20))
    """Plate length (x) and width (y)."""
    handle_m: tuple[Range, Range] = ((0.09, 0.11), (0.045, 0.055))
    """Handle length (x) and width (y)."""
    thickness_m: Range = (0.018, 0.022)
    mass_kg: Range = (0.20, 0.40)
    friction: Range = (0.25, 0.45)
    gap_m: Range = (0.04, 0.08)
    """How far the handle's tip starts behind the table edge."""
    y_m: Range = (-0.04, 0.04)
    yaw_deg: Range = (-8.0, 8.0)
    rgba: RGBA = (0.72, 0.52, 0.30, 1.0)


class PushPickBoardScoring(StrictModel):
    min_overhang_m: float = Field(0.07, gt=0)
    """The handle must stick out over the edge at least this far before the gripper can reach round it."""
    lift_m: float = Field(0.05, gt=0)
    """Success: the board's lowest point this high above the table, pinched by both fingers."""


class ForceSection(StrictModel):
    target_n: float = Field(5.0, gt=0)
    tolerance_n: float = Field(1.0, gt=0)
    duration_s: float = Field(2.0, gt=0)
    """Success: the pushing force stays within target ± tolerance for this long without a break."""


class WallSection(StrictModel):
    """A fixed wall (push-force) or low curb (flip-wall) across the table at x = x_m."""

    x_m: float = 0.20
    height_m: float = Field(0.06, gt=0)
    thickness_m: float = Field(0.03, gt=0)
    half_y_m: float = Field(0.15, gt=0)


class ClutterSection(StrictModel):
    distractors: int = Field(3, ge=0, le=6)
    size_m: Range = (0.035, 0.05)
    """Cube edge of each distractor."""
    mass_kg: Range = (0.1, 0.3)
    ring_m: Range = (0.075, 0.09)
    """Distance of each distractor's centre from the target's."""
    goal_m: tuple[float, float] = (-0.05, 0.18)
    goal_tol_m: float = Field(0.03, gt=0)


class ClutterScoring(StrictModel):
    max_disturb_m: float = Field(0.03, gt=0)
    """No distractor may end farther than this from where it started."""


class FlipScoring(StrictModel):
    flip_deg: float = Field(70.0, gt=0, lt=180)
    """Success: the box's up axis turned at least this far, and the box at rest on a face."""


class PickScoring(StrictModel):
    lift_m: float = Field(0.05, gt=0)


class ContactConfig(StrictModel):
    """Sections every contact task shares; each task adds its objects and scoring."""

    effector: EffectorSection = EffectorSection()
    table: TableSection = TableSection()
    sim: SimSection = SimSection()
    control: ControlSection = ControlSection()
    sysid: SysIdSection = SysIdSection()
    coral: CoralSection = CoralSection()
    camera: CameraSection = CameraSection()
    perception: PerceptionSection = PerceptionSection()


class PushPickBoardConfig(ContactConfig):
    effector: EffectorSection = EffectorSection(workspace_z_m=(-0.05, 0.30), grip_force_n=40.0)
    """The fingertips may go below the table top (beyond its edge; the table still stops them), and the
    gripper squeezes harder: a board held by its handle pulls on the pinch with its whole lever arm."""
    sim: SimSection = SimSection(impratio=10.0)
    """Stiffer friction (MuJoCo's advice for grasping): at impratio 1 a board hanging from its handle
    creeps round the pinch under its own lever arm."""
    board: BoardSection = BoardSection()
    scoring: PushPickBoardScoring = PushPickBoardScoring()
    control: ControlSection = ControlSection(episode_s=18.0)


class PickBoxConfig(ContactConfig):
    box: BoxSection = BoxSection(size_m=((0.04, 0.055), (0.04, 0.055), (0.04, 0.06)), mass_kg=(0.1, 0.4),
                                 friction=(0.3, 0.7), x_m=(0.0, 0.12), y_m=(-0.1, 0.1), yaw_deg=(-30, 30))
    scoring: PickScoring = PickScoring()
    control: ControlSection = ControlSection(episode_s=8.0)


class PickClutterConfig(ContactConfig):
    box: BoxSection = BoxSection(size_m=((0.04, 0.05), (0.04, 0.05), (0.04, 0.06)), mass_kg=(0.1, 0.3),
                                 friction=(0.3, 0.7), x_m=(0.05, 0.12), y_m=(-0.12, -0.04), yaw_deg=(-20, 20),
                                 rgba=(0.15, 0.6, 0.25, 1.0))
    clutter: ClutterSection = ClutterSection()
    scoring: ClutterScoring = ClutterScoring()
    control: ControlSection = ControlSection(episode_s=12.0)


class PushForceConfig(ContactConfig):
    box: BoxSection = BoxSection(size_m=((0.05, 0.07), (0.06, 0.08), (0.04, 0.06)), mass_kg=(0.3, 0.8),
                                 friction=(0.3, 0.6), x_m=(0.0, 0.06), y_m=(-0.05, 0.05), yaw_deg=(-10, 10),
                                 rgba=(0.2, 0.4, 0.85, 1.0))
    wall: WallSection = WallSection(x_m=0.20)
    force: ForceSection = ForceSection()
    control: ControlSection = ControlSection(episode_s=10.0)


class FlipBoxConfig(ContactConfig):
    box: BoxSection = BoxSection(size_m=((0.05, 0.06), (0.06, 0.08), (0.09, 0.11)), mass_kg=(0.1, 0.3),
                                 friction=(0.5, 0.8), x_m=(0.0, 0.08), y_m=(-0.06, 0.06), yaw_deg=(-10, 10),
                                 rgba=(0.8, 0.2, 0.5, 1.0))
    scoring: FlipScoring = FlipScoring()
    control: ControlSection = ControlSection(episode_s=8.0)


class FlipWallConfig(ContactConfig):
    box: BoxSection = BoxSection(size_m=((0.09, 0.11), (0.07, 0.09), (0.045, 0.055)), mass_kg=(0.1, 0.3),
                                 friction=(0.4, 0.7), x_m=(0.05, 0.09), y_m=(-0.04, 0.04), yaw_deg=(-8, 8),
                                 rgba=(0.55, 0.3, 0.8, 1.0))
    wall: WallSection = WallSection(x_m=0.20, height_m=0.015, thickness_m=0.03)
    scoring: FlipScoring = FlipScoring()
    control: ControlSection = ControlSection(episode_s=10.0)
