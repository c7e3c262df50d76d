"""Task `pour-single`: pour water from the bottle into the cup with the right arm (paper, appendix B).

What counts as poured (the paper's criterion; no liquid is simulated): at some instant
the bottle is tilted to the pouring orientation (axis at least `scoring.pour_tilt_deg`
from vertical) with its mouth above the cup's rim and within the cup's inner radius
of its axis. Success: poured, then at the end the bottle stands upright on the table,
at rest, released by both grippers, and the cup is still upright.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco

from kintsugi.core.config import StrictModel
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.spec import TaskSpec, at_rest, held, on_table, tilt_deg, upright
from kintsugi.worlds.tabletop.world import TabletopWorld, resolve

POUR_SIDE_M = 0.10
"""The grasp point sits this far beside the cup, so the tilted bottle's mouth is over it."""
POUR_HEIGHT_M = 0.14
"""Grasp point height above the cup's centroid while pouring."""
POUR_ANGLE_DEG = -100.0
"""Right arm, gripper pointing +x: a negative turn about the approach axis tips the mouth towards +y."""
SIDE_RPY_FORWARD = (0.0, 90.0, 0.0)
"""Gripper horizontal, pointing +x, fingers closing along y: carries an upright bottle."""


def script(obs: Any) -> list[dict[str, Any]]:
    start = obs.objects["bottle"].centroid
    return [
        {"action": "grasp", "arm": "right", "obj": "bottle", "pre_grasp_offset": 0.08},
        {"action": "move_by_offset", "arm": "right", "dxyz": (0.0, 0.0, 0.12)},
        {"action": "move_to_obj", "arm": "right", "obj": "cup", "offset": (0.0, -POUR_SIDE_M, POUR_HEIGHT_M),
         "rpy_deg": SIDE_RPY_FORWARD},
        {"action": "rotate_eef", "arm": "right", "angle_deg": POUR_ANGLE_DEG, "axis": "approach"},
        {"action": "rotate_eef", "arm": "right", "angle_deg": -POUR_ANGLE_DEG, "axis": "approach"},
        {"action": "place", "arm": "right", "x": start[0], "y": start[1]},
        {"action": "back", "arm": "right"},
    ]


class PourDetails(StrictModel):
    """Task-specific figures of a pour-single trial (the record's `details`)."""

    poured: bool
    max_tilt_over_cup_deg: float
    """Largest bottle tilt seen while its mouth was above the cup's opening."""
    max_tilt_deg: float
    bottle_tilt_deg: float
    bottle_on_table: bool
    bottle_at_rest: bool
    bottle_released: bool
    cup_upright: bool


class PourScorer:
    def __init__(self, cfg: TabletopConfig) -> None:
        self.cfg = cfg
        cup = cfg.objects.cup.size_m
        self.cup_inner = cup[0] - cup[2]
        self.cup_half = cup[1]
        self.poured = False
        self.max_tilt_over_cup = 0.0
        self.max_tilt = 0.0
        self._ids: tuple[int, int, int] | None = None

    def watch(self, world: TabletopWorld) -> None:
        if self._ids is None:
            self._ids = (world.bodies["bottle"], world.bodies["cup"],
                         resolve(world.model, mujoco.mjtObj.mjOBJ_SITE, "bottle_mouth"))
        bottle, cup, mouth_id = self._ids
        d = world.data
        axis = d.xmat[bottle].reshape(3, 3)[:, 2]
        tilt = tilt_deg(axis)
        self.max_tilt = max(self.max_tilt, tilt)
        mouth, rim = d.site_xpos[mouth_id], d.xpos[cup]
        over = (math.hypot(mouth[0] - rim[0], mouth[1] - rim[1]) <= self.cup_inner
                and mouth[2] > rim[2] + self.cup_half)
        if over:
            self.max_tilt_over_cup = max(self.max_tilt_over_cup, tilt)
            self.poured |= tilt >= self.cfg.scoring.pour_tilt_deg

    def finish(self, world: TabletopWorld) -> tuple[bool, PourDetails]:
        truth = world.ground_truth()
        sc = self.cfg.scoring
        rest_h = shape_of("bottle", self.cfg.objects).rest_height
        details = PourDetails(
            poured=self.poured, max_tilt_over_cup_deg=round(self.max_tilt_over_cup, 3),
            max_tilt_deg=round(self.max_tilt, 3), bottle_tilt_deg=round(truth.objects["bottle"].tilt_deg, 3),
            bottle_on_table=on_table(truth, "bottle", rest_h) and upright(truth, "bottle", sc.upright_tol_deg),
            bottle_at_rest=at_rest(truth, "bottle", sc.rest_speed_m_s),
            bottle_released=not held(truth, "bottle"),
            cup_upright=upright(truth, "cup", sc.upright_tol_deg),
        )
        ok = all((details.poured, details.bottle_on_table, details.bottle_at_rest, details.bottle_released,
                  details.cup_upright))
        return bool(ok), details


SPEC = TaskSpec(
    name="pour-single",
    description="single-arm pour water: grasp the bottle, tilt it over the cup, place it back upright (system B)",
    objects=("bottle", "cup"),
    instruction="Pour water from the bottle into the cup using the right arm, then put the bottle back "
                "upright on the table.",
    goal=("poured(bottle, cup)", "upright(bottle)", "on_table(bottle)", "released(bottle)", "upright(cup)"),
    script=script,
    scorer=PourScorer,
    shift=("cup", (0, 2)),
    knock=("bottle", (0, 0)),
)
