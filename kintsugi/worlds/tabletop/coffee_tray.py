"""Task `coffee-tray`: put the coffee capsule into the tray, then carry the tray forward with both
arms (paper, appendix B).

Success at the end: the capsule stands upright (on either end: nothing tells them apart) on the tray's floor,
inside its rims; the tray lies flat on the table with its centre in `targets.tray_forward`; both are at rest
and released.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.tabletop.config import Region, TabletopConfig
from kintsugi.worlds.tabletop.objects import TRAY_WALL, shape_of
from kintsugi.worlds.tabletop.planning import Planner
from kintsugi.worlds.tabletop.spec import TaskSpec, at_rest, held, in_region, on_table, region_center, upright
from kintsugi.worlds.tabletop.world import TabletopWorld

CAPSULE_AT = (-0.03, 0.0)
"""Where the script puts the capsule, in the tray (x, y from its centre): clear of the rims the arms take."""
RIM_TAKE_X = 0.05
"""The arms take the side rims this far forward of the tray's centre."""
RIM_HOLD_Z = 0.025
"""Grasp point above the tray's centre: the pads pinch the rim's upper centimetre, clear of the floor."""
FLOOR_CLEAR_M = 0.008
LIFT_M = 0.03
FORWARD = (0.56, 0.0)


def _offset(frame: np.ndarray, centre: np.ndarray, point: np.ndarray) -> tuple[float, float, float]:
    """A world point as an offset in an object's frame (what `grasp_offset` takes)."""
    return tuple(float(v) for v in frame.T @ (point - centre))


def script(obs: Any) -> list[dict[str, Any]]:
    tray = obs.objects["tray"]
    centre = np.array(tray.centroid)
    frame = Planner.object_frame(tray)
    rim_y = 0.08 - TRAY_WALL / 2  # nominal tray half width, as the task's object catalogue gives it
    takes = {arm: _offset(frame, centre, centre + np.array([RIM_TAKE_X, side * rim_y, RIM_HOLD_Z]))
             for arm, side in (("left", 1.0), ("right", -1.0))}
    move = (FORWARD[0] - centre[0], FORWARD[1] - centre[1], 0.0)

    def both(action: dict[str, Any], per_arm: dict[str, dict[str, Any]] | None = None) -> dict[str, Any]:
        return {"action": "drive", **{arm: {**action, "arm": arm, **(per_arm or {}).get(arm, {})}
                                      for arm in ("left", "right")}}

    return [
        {"action": "grasp", "arm": "left", "obj": "capsule", "pre_grasp_offset": 0.06},
        {"action": "move_by_offset", "arm": "left", "dxyz": (0.0, 0.0, 0.08)},
        {"action": "place", "arm": "left", "x": float(centre[0] + CAPSULE_AT[0]), "y": float(centre[1] + CAPSULE_AT[1]),
         "z_offset": TRAY_WALL + FLOOR_CLEAR_M},
        both({"action": "grasp", "obj": "tray", "pre_grasp_offset": 0.05},
             {arm: {"grasp_offset": takes[arm]} for arm in takes}),
        both({"action": "move_by_offset", "dxyz": (0.0, 0.0, LIFT_M)}),
        both({"action": "move_by_offset", "dxyz": move}),
        both({"action": "move_by_offset", "dxyz": (0.0, 0.0, -LIFT_M)}),
        both({"action": "open_gripper"}),
        both({"action": "move_by_offset", "dxyz": (0.0, 0.0, 0.06)}),
        both({"action": "back"}),
    ]


class CoffeeDetails(StrictModel):
    capsule_in_tray: bool
    """Centre inside the rims, resting on the floor."""
    capsule_upright: bool
    capsule_offset_m: tuple[float, float, float]
    """Capsule centre relative to the tray's centre."""
    tray_in_region: bool
    tray_offset_m: tuple[float, float]
    tray_flat: bool
    at_rest: bool
    released: bool


class CoffeeScorer:
    def __init__(self, cfg: TabletopConfig) -> None:
        self.cfg = cfg

    def watch(self, world: TabletopWorld) -> None:
        """Only the final scene counts."""

    def finish(self, world: TabletopWorld) -> tuple[bool, CoffeeDetails]:
        truth = world.ground_truth()
        sc, objs = self.cfg.scoring, self.cfg.objects
        tray, cap = shape_of("tray", objs), shape_of("capsule", objs)
        t, c = truth.objects["tray"], truth.objects["capsule"]
        w, x, y, z = t.quat
        rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        rel = rot.T @ (np.array(c.pos) - np.array(t.pos))
        inner = np.array(tray.half_extents[:2]) - TRAY_WALL - cap.radius
        floor_z = -tray.half_extents[2] + TRAY_WALL + cap.half_height  # capsule centre on the floor, tray frame
        d = CoffeeDetails(
            capsule_in_tray=bool(np.all(np.abs(rel[:2]) <= inner) and abs(rel[2] - floor_z) <= 0.005),
            capsule_upright=upright(truth, "capsule", sc.upright_tol_deg, cap),
            capsule_offset_m=tuple(round(float(v), 4) for v in rel),
            tray_in_region=in_region(self.cfg, "tray_forward", truth, "tray"),
            tray_offset_m=tuple(round(float(v), 4) for v in np.array(t.pos[:2])
                                - region_center(self.cfg, "tray_forward", truth)),
            tray_flat=upright(truth, "tray", sc.upright_tol_deg) and on_table(truth, "tray", tray.rest_height),
            at_rest=at_rest(truth, "tray", sc.rest_speed_m_s) and at_rest(truth, "capsule", sc.rest_speed_m_s),
            released=not held(truth, "tray") and not held(truth, "capsule"))
        ok = (d.capsule_in_tray and d.capsule_upright and d.tray_in_region and d.tray_flat and d.at_rest
              and d.released)
        return bool(ok), d


SPEC = TaskSpec(
    name="coffee-tray",
    description="setup coffee tray: capsule into the tray (left arm), then the tray forward with both arms (system B)",
    objects=("capsule", "tray"),
    instruction="Put the coffee capsule upright into the tray with the left arm, then take the tray by its side "
                "rims with both arms and set it down in the green region in front.",
    goal=("inside(capsule, tray)", "upright(capsule)", "in_region(tray, tray_forward)", "flat(tray)",
          "released(capsule)", "released(tray)"),
    script=script,
    scorer=CoffeeScorer,
    targets=("tray_forward",),
    regions={"tray_forward": Region(center_m=FORWARD, half_m=(0.03, 0.03))},
    shift=("tray", (0, 2)),
    knock=("capsule", (0, 0)),
)
