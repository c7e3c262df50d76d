"""Task `pour-dual`: the left arm holds the cup up, the right arm pours into it (paper, appendix B).

Poured means what it means in pour-single (no liquid is simulated): at some instant the bottle
is tilted to the pouring orientation with its mouth above the cup's opening, wherever the
cup is held. Success: poured, then at the end both the bottle and the cup stand upright on
the table, at rest, released by both grippers.
"""

from __future__ import annotations

from typing import Any

from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.pour_single import (
    POUR_ANGLE_DEG,
    POUR_HEIGHT_M,
    POUR_SIDE_M,
    SIDE_RPY_FORWARD,
    PourDetails,
    PourScorer,
)
from kintsugi.worlds.tabletop.spec import TaskSpec, at_rest, held, on_table, upright
from kintsugi.worlds.tabletop.world import TabletopWorld

RECEIVE_XYZ = (0.46, 0.06, 0.16)
"""Where the left arm holds the cup (its grasp point, keeping the grasp's orientation) while the right arm pours."""
CUP_GRASP_YAW_DEG = -90.0
"""The left arm takes the cup from its left side (gripper pointing -y): its wrist and forearm then stay
on the far side of the cup from the bottle tipping in from the right."""
LIFT_M = 0.10
BACK_OFF_M = 0.08


def _drive(left: dict[str, Any] | None, right: dict[str, Any] | None) -> dict[str, Any]:
    return {"action": "drive", "left": left and {**left, "arm": "left"}, "right": right and {**right, "arm": "right"}}


def script(obs: Any) -> list[dict[str, Any]]:
    bottle, cup = obs.objects["bottle"].centroid, obs.objects["cup"].centroid
    up = {"action": "move_by_offset", "dxyz": (0.0, 0.0, LIFT_M)}
    return [
        _drive({"action": "grasp", "obj": "cup", "yaw_deg": CUP_GRASP_YAW_DEG}, {"action": "grasp", "obj": "bottle"}),
        _drive(up, up),
        {"action": "move_to_target", "arm": "left", "xyz": RECEIVE_XYZ},
        {"action": "move_to_obj", "arm": "right", "obj": "cup", "offset": (0.0, -POUR_SIDE_M, POUR_HEIGHT_M),
         "rpy_deg": SIDE_RPY_FORWARD},
        {"action": "rotate_eef", "arm": "right", "angle_deg": POUR_ANGLE_DEG, "axis": "approach"},
        {"action": "rotate_eef", "arm": "right", "angle_deg": -POUR_ANGLE_DEG, "axis": "approach"},
        # Back the bottle away from the cup first: the two places move in joint space at once.
        {"action": "move_by_offset", "arm": "right", "dxyz": (0.0, -BACK_OFF_M, 0.0)},
        _drive({"action": "place", "x": cup[0], "y": cup[1]}, {"action": "place", "x": bottle[0], "y": bottle[1]}),
        _drive({"action": "back"}, {"action": "back"}),
    ]


class DualPourDetails(PourDetails):
    """pour-single's figures plus whether the cup was put back (upright, on the table, at rest, released)."""

    cup_placed: bool


class DualPourScorer(PourScorer):
    """pour-single's judge, plus: the cup too ends upright on the table, at rest and released."""

    def finish(self, world: TabletopWorld) -> tuple[bool, Any]:
        ok, details = super().finish(world)
        truth = world.ground_truth()
        sc = self.cfg.scoring
        rest_h = shape_of("cup", self.cfg.objects).rest_height
        cup_placed = (on_table(truth, "cup", rest_h) and upright(truth, "cup", sc.upright_tol_deg)
                      and at_rest(truth, "cup", sc.rest_speed_m_s) and not held(truth, "cup"))
        details = DualPourDetails(**details.model_dump(), cup_placed=cup_placed)
        return bool(ok and cup_placed), details


def make_scorer(cfg: TabletopConfig) -> DualPourScorer:
    return DualPourScorer(cfg)


SPEC = TaskSpec(
    name="pour-dual",
    description="dual-arm pour water: the left arm lifts the cup, the right pours into it, both put back (system B)",
    objects=("bottle", "cup"),
    instruction="Pick up the cup with the left arm and the bottle with the right arm, hold the cup up, pour water "
                "from the bottle into it, then put both back upright on the table.",
    goal=("poured(bottle, cup)", "upright(bottle)", "on_table(bottle)", "released(bottle)",
          "upright(cup)", "on_table(cup)", "released(cup)"),
    script=script,
    scorer=make_scorer,
    shift=("cup", (0, 0)),
    knock=("bottle", (0, 0)),
)
