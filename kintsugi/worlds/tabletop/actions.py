"""The paper's atomic actions (Table IV) as typed calls, parsed and validated before anything moves.

An action is a dict such as `{"action": "grasp", "arm": "right", "obj": "bottle"}`.
`parse_action` turns it into one of the models below or raises one `ActionError`
naming the action and the field (unknown action, missing or wrong-typed argument,
unknown object). Units: metres and degrees, world frame unless a field says otherwise.
Orientations (`rpy_deg`) are extrinsic x-y-z angles of the gripper frame, whose z axis
is the approach direction and y axis the fingers' closing direction: (180, 0, 0)
points the gripper straight down.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Sequence, Union

from pydantic import Field, TypeAdapter, ValidationError, model_validator

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import KintsugiError

Arm = Literal["left", "right"]
Vec3 = tuple[float, float, float]



class PlanError(KintsugiError):
    """An action cannot be carried out (unreachable pose, object not visible); nothing moved."""

    def __init__(self, message: str, ik_failed: bool = False, clipped: bool = False, unseen: bool = False) -> None:
        super().__init__(message)
        self.ik_failed = ik_failed
        self.clipped = clipped
        self.unseen = unseen


class ActionError(KintsugiError):
    """An action call is malformed (name, argument, object): nothing was executed."""


class _Action(StrictModel):
    arm: Arm

    @property
    def objects(self) -> tuple[str, ...]:
        """Object names this action refers to (checked against the scene)."""
        obj = getattr(self, "obj", None)
        return (obj,) if obj else ()


class Grasp(_Action):
    """Approach `obj` from `pre_grasp_offset` back along the approach axis, close on it.

    An upright tall object (bottle, cup) is taken side-on; a fallen or flat one top-down,
    across its principal axis. `grasp_offset` shifts the grasp point (object frame)."""

    action: Literal["grasp"] = "grasp"
    obj: str
    pre_grasp_offset: float = Field(0.08, ge=0.0, le=0.3)
    grasp_offset: Vec3 | None = None
    yaw_deg: float | None = Field(None, ge=-180.0, le=180.0)
    """Orientation hint: the heading (from +x, about the vertical) of the approach axis for a side grasp,
    or of the gripper's x axis for a top-down one. Default: away from the arm's base (and, top-down,
    closing across the object's principal axis)."""
    close_s: float = Field(0.0, ge=0.0, le=2.0)
    """Close gently: the fingers are brought closed over this many seconds (0: at once)."""
    pitch_deg: float = Field(0.0, ge=-60.0, le=60.0)
    """A top-down grasp only: tilt the hand about its closing axis by this much (a hand leaning in from the
    arm's side reaches farther out than one pointing straight down)."""


class OpenGripper(_Action):
    action: Literal["open_gripper"] = "open_gripper"


class CloseGripper(_Action):
    action: Literal["close_gripper"] = "close_gripper"
    close_s: float = Field(0.0, ge=0.0, le=2.0)
    """Close gently: the fingers are brought closed over this many seconds (0: at once)."""


class MoveToObj(_Action):
    """Move the tool centre point to `offset` in the object's frame (origin at its centroid,
    z up, x along its principal axis when that lies flat, else world x); keep the current
    orientation unless `rpy_deg` is given."""

    action: Literal["move_to_obj"] = "move_to_obj"
    obj: str
    offset: Vec3 = (0.0, 0.0, 0.0)
    rpy_deg: Vec3 | None = None


class MoveToTarget(_Action):
    """Move the tool centre point to an absolute position (and orientation, if given)."""

    action: Literal["move_to_target"] = "move_to_target"
    xyz: Vec3
    rpy_deg: Vec3 | None = None


class MoveByOffset(_Action):
    """Move in a straight line by `dxyz` and turn by `drpy_deg`, in the world or gripper frame."""

    action: Literal["move_by_offset"] = "move_by_offset"
    dxyz: Vec3 = (0.0, 0.0, 0.0)
    drpy_deg: Vec3 = (0.0, 0.0, 0.0)
    frame: Literal["world", "gripper"] = "world"


class RotateEef(_Action):
    """Turn the gripper about its own axis (approach: tilt-to-pour and back) around the grasp point."""

    action: Literal["rotate_eef"] = "rotate_eef"
    angle_deg: float = Field(ge=-270.0, le=270.0)
    axis: Literal["approach", "closing", "normal"] = "approach"


class Place(_Action):
    """Carry the held object over (x, y), lower it until it rests `z_offset` above the table,
    release it and back the gripper away."""

    action: Literal["place"] = "place"
    x: float
    y: float
    z_offset: float = Field(0.0, ge=0.0, le=0.3)


class Push(_Action):
    """Push `obj` across the table by `dxy` (world frame) with the closed hand: it comes down behind the object
    (on the side away from where it is pushed), moves along `dxy` and rises. `contact_deg` says where the pads
    meet that far side: 90 low beside it, less higher up, 0 on its top (pressing down on it and drawing it
    along, for a far side beyond the arm's reach or the workspace). `pitch_deg` tilts the hand about its
    closing axis (a hand leaning in reaches farther out)."""

    action: Literal["push"] = "push"
    obj: str
    dxy: tuple[float, float]
    contact_deg: float = Field(90.0, ge=0.0, le=90.0)
    pitch_deg: float = Field(0.0, ge=-60.0, le=60.0)


class Back(_Action):
    """Return the arm to its home configuration."""

    action: Literal["back"] = "back"
    rise_m: float = Field(0.0, ge=0.0, le=0.3)
    """First raise the gripper this far straight up (its fingers leave whatever they are beside or above before
    the joint-space move home sweeps them), as far as the arm follows that line."""


ArmAction = Annotated[
    Union[Grasp, OpenGripper, CloseGripper, MoveToObj, MoveToTarget, MoveByOffset, RotateEef, Place, Push, Back],
    Field(discriminator="action"),
]


class Drive(StrictModel):
    """Both arms at once (either may be None); they step simultaneously until both finish."""

    action: Literal["drive"] = "drive"
    left: ArmAction | None = None
    right: ArmAction | None = None

    @model_validator(mode="after")
    def _arms_match(self) -> Drive:
        if self.left is None and self.right is None:
            raise ValueError("drive needs a left or a right action")
        for slot in ("left", "right"):
            inner = getattr(self, slot)
            if inner is not None and inner.arm != slot:
                raise ValueError(f"drive.{slot} is an action for the {inner.arm} arm")
        return self

    @property
    def objects(self) -> tuple[str, ...]:
        return tuple(o for a in (self.left, self.right) if a is not None for o in a.objects)


Action = Annotated[Union[ArmAction, Drive], Field(discriminator="action")]
ACTION_NAMES = ("grasp", "open_gripper", "close_gripper", "move_to_obj", "move_to_target", "move_by_offset",
                "rotate_eef", "place", "push", "back", "drive")
_ADAPTER: TypeAdapter = TypeAdapter(Action)


def _where(loc: tuple[Any, ...]) -> str:
    # pydantic puts the discriminator value in the location (e.g. ('grasp', 'obj')); keep field names only.
    parts = [str(p) for p in loc if str(p) not in ACTION_NAMES]
    return ".".join(parts) or "(action)"


def parse_action(data: dict[str, Any] | Any, objects: Sequence[str]) -> Any:
    """Validate one action call; raise ActionError naming the problem. `objects`: the scene's objects."""
    if not isinstance(data, dict):
        raise ActionError(f"an action must be a mapping with an 'action' key, got {type(data).__name__}")
    name = data.get("action")
    if name not in ACTION_NAMES:
        raise ActionError(f"unknown action {name!r}; known: {', '.join(ACTION_NAMES)}")
    try:
        action = _ADAPTER.validate_python(data)
    except ValidationError as exc:
        problems = "; ".join(f"{_where(e['loc'])}: {e['msg']}" for e in exc.errors())
        raise ActionError(f"bad arguments for {name}: {problems}") from None
    for obj in action.objects:
        if obj not in objects:
            raise ActionError(f"{name}: unknown object {obj!r}; objects in this scene: {', '.join(objects)}")
    return action
