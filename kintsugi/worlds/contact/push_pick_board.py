"""T1 push-pick-board: push a cutting board until its handle overhangs the table edge, then pick it.

The board is a flat plate (wider and longer than the gripper opens) with a narrow handle on
its +x side, lying flat with the handle's tip `board.gap_m` behind the table's front edge.
The gripper's fingers can only close round the handle, and a pinch that holds the board's
weight against its lever arm needs the pads over the handle's whole thickness, i.e. the
fingertips below the board: that is possible only beyond the table edge, so the handle must
first be pushed out over it. This task's effector may therefore go below the table top
(`effector.workspace_z_m` starts below 0); the table itself still stops the fingers.

Success (ground truth, at the end): the board's lowest point is `scoring.lift_m` above the
table top, both finger pads touch it, and it is at rest (below 2 cm/s and 0.3 rad/s).
The largest handle overhang reached is recorded.
"""

from __future__ import annotations

import math

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import PushPickBoardConfig
from kintsugi.worlds.contact.objects import Geometry, Physics, Placement, board
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup, lowest_z, nominal
from kintsugi.worlds.contact.world import EvaluationWorld, Scene, rotate

AT_REST_M_S = 0.02
AT_REST_RAD_S = 0.3


def handle_tip_local(geo: Geometry) -> np.ndarray:
    """The handle's outer end (object frame): the two corners of its +x face at mid-thickness."""
    h = geo.parts[1]
    x = h.pos[0] + h.half[0]
    return np.array([[x, -h.half[1], 0.0], [x, h.half[1], 0.0]])


def overhang(pos: np.ndarray, quat: np.ndarray, geo: Geometry, edge_x: float) -> np.ndarray:
    """How far the handle's tip sticks out past the table edge (m, negative = behind it), for
    poses (..., 3) / (..., 4): the less exposed of its two tip corners."""
    tip = handle_tip_local(geo)
    q = np.broadcast_to(quat[..., None, :], (*quat.shape[:-1], 2, 4))
    pts = pos[..., None, :] + rotate(q, np.broadcast_to(tip, (*quat.shape[:-1], 2, 3)))
    return pts[..., 0].min(axis=-1) - edge_x


class BoardDetails(StrictModel):
    lowest_z_m: float
    """Height of the board's lowest corner above the table at the end."""
    max_lowest_z_m: float
    pinched: bool
    speed_m_s: float
    max_overhang_m: float
    """Largest handle overhang past the table edge during the attempt."""


class BoardScorer:
    def __init__(self, cfg: PushPickBoardConfig, setup: TrialSetup) -> None:
        self.cfg = cfg
        self.geo = setup.scene.geometry["board"]
        self.reset()

    def reset(self) -> None:
        self.max_z, self.max_over = 0.0, -math.inf

    def watch(self, world: EvaluationWorld) -> None:
        pos, quat = world.object_pose("board")
        self.max_over = max(self.max_over, float(overhang(pos, quat, self.geo, self.cfg.table.edge_x_m)))
        self.max_z = max(self.max_z, lowest_z(world, "board"))

    def finish(self, world: EvaluationWorld) -> tuple[bool, BoardDetails]:
        z = lowest_z(world, "board")
        pinched = world.pinched("board")
        lin, ang = world.object_velocity("board")
        pos, quat = world.object_pose("board")
        over = max(self.max_over, float(overhang(pos, quat, self.geo, self.cfg.table.edge_x_m)))
        ok = (z >= self.cfg.scoring.lift_m and pinched and np.linalg.norm(lin) < AT_REST_M_S
              and np.linalg.norm(ang) < AT_REST_RAD_S)
        return bool(ok), BoardDetails(lowest_z_m=round(z, 5), max_lowest_z_m=round(max(self.max_z, z), 5),
                                      pinched=pinched, speed_m_s=round(float(np.linalg.norm(lin)), 4),
                                      max_overhang_m=round(over, 5))


def build(cfg: PushPickBoardConfig, d: Drawer) -> TrialSetup:
    b = cfg.board
    plate = (d.physics("board.plate_x_m", b.plate_m[0]), d.physics("board.plate_y_m", b.plate_m[1]))
    handle = (d.physics("board.handle_x_m", b.handle_m[0]), d.physics("board.handle_y_m", b.handle_m[1]))
    thick = d.physics("board.thickness_m", b.thickness_m)
    truth = Physics(mass_kg=d.physics("board.mass_kg", b.mass_kg), friction=d.physics("board.friction", b.friction))
    gap = d.pose("board.gap_m", b.gap_m)
    y = d.pose("board.y_m", b.y_m)
    yaw = d.pose("board.yaw_deg", b.yaw_deg)
    reach = plate[0] / 2 + handle[0]  # plate centre -> handle tip
    x = cfg.table.edge_x_m - gap - math.cos(math.radians(yaw)) * reach
    geo = board(plate, handle, thick, b.rgba)
    scene = Scene(geometry={"board": geo}, start={"board": Placement(x=x, y=y, yaw_deg=yaw)})
    return TrialSetup(scene=scene, truth={"board": truth}, nominal={"board": nominal(b.mass_kg, b.friction)},
                      params=dict(d.drawn))


TASK = ContactTaskDef(
    name="push-pick-board",
    description="T1: push a cutting board until its handle overhangs the table edge, then pick it (system C)",
    instruction="Push the cutting board until its handle sticks out over the table edge, then pick the board up "
                "by the handle.",
    config_type=PushPickBoardConfig, build=build, scorer=BoardScorer, target="board",
    reference_method="expert-fsm",
)
