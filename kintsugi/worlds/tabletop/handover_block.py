"""Task `handover-block`: the left arm picks the block up and hands it to the right arm, which
places it in the target region (paper, appendix B).

Success (appendix B: "transferred between arms and placed within the target region without
being dropped"; every criterion "satisfied at the end of execution"): the block was held by both
grippers at once at some instant (the handover), then by the right alone; its last release was a
place, not a drop: the right gripper let it go with its lowest corner at most `PLACED_ABOVE_M`
above the table; it rests flat on the table, its centre inside `targets.block`, at rest and released.

A drop on the way (injected, or the handover fumbled) that the method picks up and recovers from
does not fail the trial, as in the other tasks; the details count it (`drops`). A block that
fell into the region, or was last let go by the left hand, fails.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from kintsugi.core.config import StrictModel
from kintsugi.worlds.tabletop.config import Region, TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.spec import TaskSpec, at_rest, held, in_region, region_center
from kintsugi.worlds.tabletop.world import GroundTruth, TabletopWorld

HANDOVER_XYZ = (0.42, 0.0, 0.20)
"""Where the left arm presents the block (its grasp point, gripper pointing down, fingers closing along y)."""
DOWN_CLOSING_Y = (0.0, 180.0, 0.0)
SIDE_FROM_RIGHT = (-90.0, 90.0, 0.0)
"""The right gripper horizontal, approaching along +y, fingers closing along x (across the free faces)."""
TAKE_DEPTH_M = 0.01
"""The right grasp point stops this short of the block's centre, keeping its palm off the left fingers."""
TAKE_HIGH_M = 0.012
"""...and this far above it, so that its palm (lower edge 3 cm below the grasp point) clears the table at the place."""
REGION = (0.40, -0.25)
DROP_TICKS = 5
"""Touching neither gripper, off the table, for this many control ticks in a row is a drop
(a single tick without a pad contact is the contact solver flickering, not a fall)."""
PLACED_ABOVE_M = 0.01
"""A release with the block's lowest corner at most this far above the table is a place; higher is a drop."""
HOLD_OPENING_M = 0.01
"""The fingers are at least this far apart when they hold the block (it is 5 cm wide)."""


def script(obs: Any) -> list[dict[str, Any]]:
    return [
        {"action": "grasp", "arm": "left", "obj": "block", "pre_grasp_offset": 0.06},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, 0.12)},
        {"action": "move_to_target", "arm": "left", "xyz": HANDOVER_XYZ, "rpy_deg": DOWN_CLOSING_Y},
        {"action": "move_to_obj", "arm": "right", "obj": "block", "offset": (0.0, -0.10, TAKE_HIGH_M),
         "rpy_deg": SIDE_FROM_RIGHT},
        {"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.10 - TAKE_DEPTH_M, 0.0)},
        {"action": "close_gripper", "arm": "right"},
        {"action": "open_gripper", "arm": "left"},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, 0.08)},
        {"action": "place", "arm": "right", "x": REGION[0], "y": REGION[1]},
        {"action": "drive", "left": {"action": "back", "arm": "left"}, "right": {"action": "back", "arm": "right"}},
    ]


class HandoverDetails(StrictModel):
    picked: bool
    """The left gripper held the block off the table."""
    handed_over: bool
    """Both grippers held it at once, and later the right alone."""
    drops: int
    """Falls on the way (free of both grippers, off the table, for `DROP_TICKS`), recovered or not."""
    placed: bool
    """The last release was the right gripper's, near the table: a place, not a drop."""
    release_height_m: float | None
    """The block's lowest corner above the table at its last release (None: never released after the pick)."""
    flat: bool
    in_region: bool
    offset_m: tuple[float, float]
    at_rest: bool
    released: bool


def _flat(truth: GroundTruth, obj: str, rest_h: float, tol_deg: float) -> bool:
    """A cube rests flat on any face: one body axis vertical, its centre at half the side."""
    q = truth.objects[obj].quat
    m = Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix()
    return bool(np.max(np.abs(m[2, :])) >= np.cos(np.radians(tol_deg))
                and abs(truth.objects[obj].pos[2] - rest_h) <= 0.005)


class HandoverScorer:
    def __init__(self, cfg: TabletopConfig) -> None:
        self.cfg = cfg
        shape = shape_of("block", cfg.objects)
        self.rest_h, self.half = shape.rest_height, np.asarray(shape.half_extents)
        self.picked = self.both = self.right_alone = False
        self.drops = 0
        self._free_ticks = 0
        self._holder: str | None = None
        self.release: tuple[str, float] | None = None
        """(the hand that let go last, the block's height above rest then): a let-go ends a hold of both pads."""

    def watch(self, world: TabletopWorld) -> None:
        left, right = world.pad_contacts("left")[0], world.pad_contacts("right")[0]
        # A hold: both pads on the block, apart (fingers shut on each other can press both pads on its top).
        by_left, by_right = ((contacts.get("block") == 2 and world.gripper_opening(arm) > HOLD_OPENING_M)
                             for arm, contacts in (("left", left), ("right", right)))
        z = float(world.data.xpos[world.bodies["block"]][2])
        off_table = z > self.rest_h + 0.01
        self.picked |= by_left and off_table
        self.both |= by_left and by_right
        self.right_alone |= self.both and by_right and "block" not in left
        free = "block" not in left and "block" not in right
        if by_left or by_right:  # a pad brushing the block is no hold, nor its lifting away a place
            self._holder = "right" if not by_left else "left" if not by_right else "both"
        elif self._holder is not None and self.picked:
            tilt = np.abs(world.data.xmat[world.bodies["block"]].reshape(3, 3)[2, :])
            self.release = (self._holder, z - float(tilt @ self.half))  # the table top is z = 0
            self._holder = None
        self._free_ticks = self._free_ticks + 1 if (self.picked and off_table and free) else 0
        self.drops += self._free_ticks == DROP_TICKS

    def finish(self, world: TabletopWorld) -> tuple[bool, HandoverDetails]:
        truth = world.ground_truth()
        sc = self.cfg.scoring
        d = HandoverDetails(
            picked=self.picked, handed_over=self.both and self.right_alone, drops=self.drops,
            placed=self.release is not None and self.release[0] == "right" and self.release[1] <= PLACED_ABOVE_M,
            release_height_m=None if self.release is None else round(float(self.release[1]), 4),
            flat=_flat(truth, "block", self.rest_h, sc.upright_tol_deg),
            in_region=in_region(self.cfg, "block", truth, "block"),
            offset_m=tuple(round(float(v), 4) for v in np.array(truth.objects["block"].pos[:2])
                           - region_center(self.cfg, "block", truth)),
            at_rest=at_rest(truth, "block", sc.rest_speed_m_s), released=not held(truth, "block"))
        ok = d.picked and d.handed_over and d.placed and d.flat and d.in_region and d.at_rest and d.released
        return bool(ok), d


SPEC = TaskSpec(
    name="handover-block",
    description="handover block: the left arm hands the block to the right, which places it in the region (system B)",
    objects=("block",),
    instruction="Pick up the block with the left arm, hand it over to the right arm, and place it in the "
                "green target region with the right arm without dropping it.",
    goal=("handed_over(block, left, right)", "not dropped(block)", "in_region(block, target)", "flat(block)",
          "released(block)"),
    script=script,
    scorer=HandoverScorer,
    targets=("block",),
    regions={"block": Region(center_m=REGION, half_m=(0.035, 0.035))},
    shift=("block", (0, 0)),
)
