"""Typed requests and replies of system C's reasoner roles (CoRAL): physics priors and contact regions.

What a role may see is what a model would: the instruction, a camera image, and each object's label
and size as its known 3D model gives them. Never a trial's true mass or friction.
Replies are parsed strictly (unknown keys rejected); numbers a model may get wrong but that are
usable once bounded (a mass of 80 kg for a box) are clamped by `kintsugi.methods.coral.priors`, with
a note, rather than rejected.
"""

from __future__ import annotations

import math
from typing import Callable, Literal

from pydantic import Field, field_validator

from kintsugi.core.config import StrictModel

Vec3 = tuple[float, float, float]


class PartView(StrictModel):
    """One box of an object's known model (a board's plate, its handle)."""

    size_m: Vec3 = Field(description="extents of this part, metres (x, y, z)")
    offset_m: Vec3 = Field(default=(0.0, 0.0, 0.0), description="its centre in the object's frame, metres")


class ObjectView(StrictModel):
    """One object as the robot knows it before touching it."""

    label: str = Field(min_length=1, max_length=80, description="what the object is, e.g. 'cutting board'")
    size_m: Vec3 = Field(description="extents of its known model's main part, metres (x, y, z)")
    parts: list[PartView] = Field(default_factory=list, max_length=16,
                                  description="every part of its known model (empty: one part of size_m)")

    @property
    def volume_m3(self) -> float:
        """The known model's volume: the sum of its parts (a board's handle included)."""
        if self.parts:
            return float(sum(math.prod(p.size_m) for p in self.parts))
        return float(math.prod(self.size_m))

    @field_validator("size_m")
    @classmethod
    def _positive(cls, v: Vec3) -> Vec3:
        if not all(math.isfinite(x) and x > 0 for x in v):
            raise ValueError("every extent must be a positive finite number of metres")
        return v


class PriorsRequest(StrictModel):
    task: str = Field(description="the instruction")
    objects: list[ObjectView] = Field(min_length=1, max_length=32)
    image_png: bytes | None = Field(default=None, repr=False, description="a camera image of the scene")


class ObjectPrior(StrictModel):
    mass_kg: float = Field(description="estimated mass, kg")
    friction: float = Field(description="estimated sliding friction coefficient against the table")
    material: str = Field(default="", max_length=80, description="what it looks made of (free text)")


class PriorsReply(StrictModel):
    objects: dict[str, ObjectPrior] = Field(description="label -> prior, one entry per requested object")
    reasoning: str = Field(default="", max_length=2000)


class RegionSpec(StrictModel):
    """A contact region on an object, in the object's frame: candidate contact points are sampled on
    the disc of `radius` around `center`, and the hand approaches against `normal` (outward)."""

    object: str = Field(min_length=1, max_length=80)
    center: Vec3
    normal: Vec3
    radius: float

    standoff: float = Field(default=0.0, description="how far off the surface, along the normal, the tool centre "
                                                    "point sits when the fingers touch it (m)")
    drop: float = Field(default=0.0, description="how far below the point the tool centre point goes (m): it is "
                                                 "the fingertips' bottom")


# --- task formulation -------------------------------------------------------------------------------------------

class ObjectState(StrictModel):
    """An object as the tracker and its known model give it at the start: what, how big, where. Never mass."""

    name: str = Field(min_length=1, max_length=40, description="the object's name in cost code variables")
    label: str = Field(min_length=1, max_length=80)
    size_m: Vec3
    pos_m: Vec3
    yaw_deg: float
    upright_deg: float = Field(description="angle between the object's z axis and the world's up")
    shape: str = Field(default="", max_length=40, description="what shape its known model is: box, cylinder, "
                                                             "sphere, capsule, ... ('' = not told; a box)")
    colour: str = Field(default="", max_length=40, description="its colour as the camera sees it ('' = not told)")
    material: str = Field(default="", max_length=40, description="what it looks made of ('' = not told)")


class FixtureView(StrictModel):
    """A static box in the scene (a wall, a curb), world frame."""

    name: str
    lo_m: Vec3
    hi_m: Vec3
    label: str = Field(default="", max_length=80, description="what it is, e.g. 'wooden curb' ('' = its name)")


class MarkerView(StrictModel):
    """A flat goal disc on the table."""

    name: str
    x_m: float
    y_m: float
    radius_m: float
    label: str = Field(default="", max_length=80, description="what it looks like, e.g. 'green disc' ('' = its name)")


class RobotView(StrictModel):
    max_opening_m: float
    finger_length_m: float
    kp_n_per_m: float
    force_limit_n: float
    table_edge_x_m: float
    home_m: Vec3


Grip = float | Literal["open", "closed", "free"] | str


SEED_AXES = {"x": 0, "y": 1, "z": 2, "yaw": 3}
"""A stage's optional `<cost>_seed_<axis>` functions of the state at stage entry give the command (TCP x, y, z in m,
yaw in rad) its plan restarts from; the value is the actuator index."""


def seed_functions(cost: str, defined: Callable[[str], bool]) -> dict[str, int]:
    """The seed functions the code defines for a stage with this cost function: name -> actuator index."""
    return {f"{cost}_seed_{a}": i for a, i in SEED_AXES.items() if defined(f"{cost}_seed_{a}")}


class StageSpec(StrictModel):
    """One stage of a staged cost: which functions of the code give its running cost and its transition."""

    name: str = Field(min_length=1, max_length=40)
    cost: str = Field(description="name of the code's function giving the (K, T) running cost")
    done: str = Field(description="name of the code's function of the measured state: the stage is done when it "
                                  "returns true")
    grip: Grip = Field(default="free", description="gripper: 'open', 'closed', 'free' (planned), an opening in m, "
                                                   "or the name of a code function of the state at stage entry")
    keep: str | None = Field(default=None, description="name of a code function of the state at stage entry: its "
                                                      "value is the variable `kept` while the stage runs")
    region: int | None = Field(default=None, description="index into `regions`: its candidate points give the "
                                                         "`contact` variable")
    timeout_s: float = 5.0
    hold_s: float = 0.0
    press_n: float | None = Field(default=None, description="force to regulate along `press_axis` (Eq. 5 feedback)")
    press_axis: int = Field(default=0, ge=0, le=2)
    noise_scale: float = 1.0


class FormulationRequest(StrictModel):
    task: str
    objects: list[ObjectState] = Field(min_length=1, max_length=16)
    fixtures: list[FixtureView] = Field(default_factory=list)
    markers: list[MarkerView] = Field(default_factory=list)
    robot: RobotView
    priors: dict[str, ObjectPrior] = Field(description="object name -> physics belief the planning world holds")
    variables: dict[str, str] = Field(description="name -> meaning of every variable cost code may take")
    functions: dict[str, str] = Field(description="the math functions cost code may call")
    contact_strategy: bool = Field(default=True, description="false: give no regions and do not use `contact`")
    image_png: bytes | None = Field(default=None, repr=False)


class FormulationReply(StrictModel):
    source: str = Field(max_length=20_000, description="cost code: every stage's cost and done functions")
    stages: list[StageSpec] = Field(min_length=1, max_length=12)
    regions: list[RegionSpec] = Field(default_factory=list, max_length=8)
    knobs: dict[str, float] = Field(default_factory=dict, description="the weights and thresholds the code was "
                                                                      "written with (for later refinement)")
    reasoning: str = Field(default="", max_length=4000)


# --- adaptation (outer loop) -------------------------------------------------------------------------------------

class StageOutcome(StrictModel):
    name: str
    reached: bool
    seconds: float
    cost_first: float | None = None
    cost_last: float | None = None
    cost_min: float | None = None


class SysIdSummary(StrictModel):
    """The system identification's fit on the robot's own log (windows where something moved or was felt)."""

    object: str
    mass_kg: float
    friction: float
    loss_prior: float
    loss_fit: float
    windows: int
    adopted: bool = True
    """False: the log cannot identify the fit (the object never slid or hung from the hand) or it gains less than
    the replay's noise; mass_kg and friction are then the beliefs kept."""
    kept_because: str | None = None


class AttemptHistory(StrictModel):
    attempt: int
    stages: list[StageOutcome]
    failed_stage: str | None = Field(description="the stage that timed out or ran out of time; None = all done")
    max_force_n: float
    mean_press_force_n: float | None = None
    object_travel_m: dict[str, float]
    object_tilt_deg: dict[str, float]
    touch_lost_while_held: bool = False
    cost_error: str | None = None
    broken: str | None = Field(default=None, description="why the attempt failed a constraint the instruction "
                                                         "sets over the whole path (e.g. a thing it forbids "
                                                         "touching came too close); None = none broke")


class AdaptRequest(StrictModel):
    task: str
    scene: FormulationRequest = Field(description="the scene and vocabulary the code was formulated for")
    beliefs: dict[str, ObjectPrior]
    source: str
    stages: list[StageSpec]
    regions: list[RegionSpec]
    knobs: dict[str, float]
    history: list[AttemptHistory] = Field(min_length=1)
    sysid: SysIdSummary | None = None
    refine_strategy: bool = Field(default=True, description="false: correct the world model only")


class AdaptReply(StrictModel):
    diagnosis: str = Field(default="", max_length=4000)
    beliefs: dict[str, ObjectPrior] | None = Field(default=None, description="corrected physics; None keeps them")
    source: str | None = Field(default=None, max_length=20_000, description="rewritten cost code; None keeps it")
    stages: list[StageSpec] | None = None
    regions: list[RegionSpec] | None = None
    knobs: dict[str, float] | None = None
