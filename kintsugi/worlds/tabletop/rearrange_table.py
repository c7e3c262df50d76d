"""Task `rearrange-table`: put the fork left of the plate and the spoon right of it (paper, appendix B).

The two regions (`targets.fork`, `targets.spoon`) ride with the plate. Success: each utensil's
centre lies in its region, it lies flat on the table (either face up: its slabs are the same turned over,
and the instruction asks for flat), its handle runs along the plate's side
(world x, within `scoring.align_tol_deg`) with its head pointing away from the robot (+x),
it is at rest and released.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.perception.features import ObjectFeatures
from kintsugi.worlds.tabletop.config import Region, TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.spec import TaskSpec, at_rest, held, in_region, region_center, rest_level
from kintsugi.worlds.tabletop.world import TabletopWorld

LIFT_M = 0.08
BESIDE_M = 0.18
"""The script's aim: this far left / right of the plate's centre (the middle of `targets.fork` / `spoon`)."""
UTENSILS = {"fork": "left", "spoon": "right"}


def head_yaw_deg(f: ObjectFeatures) -> float:
    """Direction of the utensil's head from perceived features: the wide head pulls the cloud's
    centroid towards it, so the axis end nearer the centroid is the head."""
    c = np.array(f.centroid)
    ends = [np.array(f.extremes[k]) for k in ("axis_pos", "axis_neg")]
    near, far = sorted(ends, key=lambda e: float(np.linalg.norm(e[:2] - c[:2])))
    d = near - far
    return math.degrees(math.atan2(d[1], d[0]))


def _wrap(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0


def script(obs: Any) -> list[dict[str, Any]]:
    plate = np.array(obs.objects["plate"].centroid[:2])
    plan: dict[str, list[dict[str, Any]]] = {}
    for obj, arm in UTENSILS.items():
        side = 1.0 if obj == "fork" else -1.0
        f = obs.objects[obj]
        goal = plate + np.array([0.0, side * BESIDE_M])
        # A gripper pointing down turns the held object by minus its own turn about the approach axis.
        turn = _wrap(head_yaw_deg(f))
        # Carry it over its place before turning it: near the shoulder the wrist runs out of range.
        carry = (float(goal[0] - f.centroid[0]), float(goal[1] - f.centroid[1]), LIFT_M)
        plan[arm] = [
            {"action": "grasp", "arm": arm, "obj": obj, "pre_grasp_offset": 0.06},
            {"action": "move_by_offset", "arm": arm, "dxyz": (0.0, 0.0, LIFT_M)},
            {"action": "move_by_offset", "arm": arm, "dxyz": (carry[0], carry[1], 0.0)},
            {"action": "rotate_eef", "arm": arm, "angle_deg": turn, "axis": "approach"},
            {"action": "place", "arm": arm, "x": float(goal[0]), "y": float(goal[1])},
            {"action": "back", "arm": arm},
        ]
    return [{"action": "drive", "left": left, "right": right} for left, right in zip(plan["left"], plan["right"])]


class UtensilState(StrictModel):
    in_region: bool
    offset_m: tuple[float, float]
    """Centre minus the region's centre (x, y)."""
    flat: bool
    heading_err_deg: float
    """Angle between the head direction and +x (away from the robot)."""
    at_rest: bool
    released: bool


class RearrangeDetails(StrictModel):
    fork: UtensilState
    spoon: UtensilState


class RearrangeScorer:
    def __init__(self, cfg: TabletopConfig) -> None:
        self.cfg = cfg

    def watch(self, world: TabletopWorld) -> None:
        """Only the final scene counts."""

    def finish(self, world: TabletopWorld) -> tuple[bool, RearrangeDetails]:
        truth = world.ground_truth()
        sc = self.cfg.scoring
        states = {}
        for obj in UTENSILS:
            q = truth.objects[obj].quat
            w, x, y, z = q
            head = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z)])  # body x in the world, on the table
            heading = abs(_wrap(math.degrees(math.atan2(head[1], head[0]))))
            states[obj] = UtensilState(
                in_region=in_region(self.cfg, obj, truth, obj),
                offset_m=tuple(round(float(v), 4) for v in np.array(truth.objects[obj].pos[:2])
                               - region_center(self.cfg, obj, truth)),
                flat=rest_level(truth, obj, (sh := shape_of(obj, self.cfg.objects)).rest_height, sc.upright_tol_deg, shape=sh),
                heading_err_deg=round(heading, 3), at_rest=at_rest(truth, obj, sc.rest_speed_m_s),
                released=not held(truth, obj))
        details = RearrangeDetails(**states)
        ok = all(s.in_region and s.flat and s.heading_err_deg <= sc.align_tol_deg and s.at_rest and s.released
                 for s in states.values())
        return ok, details


SPEC = TaskSpec(
    name="rearrange-table",
    description="rearrange table: fork left of the plate, spoon right of it, heads away from the robot (system B)",
    objects=("plate", "fork", "spoon"),
    instruction="Place the fork to the left of the plate and the spoon to the right of it, each lying flat along "
                "the plate's side with its head pointing away from you. Use the left arm for the fork and the "
                "right arm for the spoon.",
    goal=("in_region(fork, beside_left(plate))", "in_region(spoon, beside_right(plate))", "flat(fork)",
          "flat(spoon)", "heading(fork, away)", "heading(spoon, away)", "released(fork)", "released(spoon)"),
    script=script,
    scorer=RearrangeScorer,
    targets=("fork", "spoon"),
    regions={"fork": Region(center_m=(0.0, 0.18), half_m=(0.04, 0.025), relative_to="plate"),
             "spoon": Region(center_m=(0.0, -0.18), half_m=(0.04, 0.025), relative_to="plate")},
    shift=("plate", (0, 2)),
)
