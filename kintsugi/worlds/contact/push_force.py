"""T4 push-force: push a box against a wall and hold a constant pushing force on it.

Success (ground truth): the force the effector's contacts exert on the box, along the push
direction (+x, toward the wall), stays within `force.target_n` ± `force.tolerance_n` for
`force.duration_s` without a break (sampled at every inner control tick, 100 Hz, with the box
within 3 mm of the wall); and the box ends touching the wall.
"""

from __future__ import annotations

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.worlds.contact.conditions import Drawer
from kintsugi.worlds.contact.config import PushForceConfig, WallSection
from kintsugi.worlds.contact.objects import Fixture
from kintsugi.worlds.contact.pick_box import draw_box
from kintsugi.worlds.contact.spec import ContactTaskDef, TrialSetup, corners
from kintsugi.worlds.contact.world import EvaluationWorld, Scene, rotate


def wall_fixture(w: WallSection) -> Fixture:
    return Fixture(half=(w.thickness_m / 2, w.half_y_m, w.height_m / 2), pos=(w.x_m, 0.0, w.height_m / 2))


def wall_face_x(w: WallSection) -> float:
    """The wall's face toward the robot."""
    return w.x_m - w.thickness_m / 2


class PushForceDetails(StrictModel):
    longest_in_band_s: float
    """Longest unbroken time the push force stayed within target ± tolerance."""
    mean_force_n: float
    """Mean push force over that stretch (0 if none)."""
    max_force_n: float
    gap_to_wall_m: float
    """Distance from the box's nearest point to the wall face at the end."""


class ForceScorer:
    def __init__(self, cfg: PushForceConfig, setup: TrialSetup) -> None:
        self.cfg = cfg
        self.face = wall_face_x(cfg.wall)
        self.corners = corners(setup.scene.geometry["box"])
        self.reset()

    def reset(self) -> None:
        self.run_s, self.best_s, self.run_sum, self.best_mean, self.max_f = 0.0, 0.0, 0.0, 0.0, 0.0
        self._last_t: float | None = None

    def watch(self, world: EvaluationWorld) -> None:
        f = float(world.pusher_force("box")[0])
        t = float(world.data.time)
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        self.max_f = max(self.max_f, f)
        fc = self.cfg.force
        if abs(f - fc.target_n) <= fc.tolerance_n and self._gap(world) < 0.003:
            self.run_s += dt
            self.run_sum += f * dt
            if self.run_s > self.best_s:
                self.best_s, self.best_mean = self.run_s, self.run_sum / max(self.run_s, 1e-9)
        else:
            self.run_s, self.run_sum = 0.0, 0.0

    def _gap(self, world: EvaluationWorld) -> float:
        pos, quat = world.object_pose("box")
        pts = pos + rotate(np.broadcast_to(quat, (len(self.corners), 4)), self.corners)
        return float(self.face - pts[:, 0].max())

    def finish(self, world: EvaluationWorld) -> tuple[bool, PushForceDetails]:
        gap = self._gap(world)
        ok = self.best_s >= self.cfg.force.duration_s - 1e-6 and gap < 0.003
        return ok, PushForceDetails(longest_in_band_s=round(self.best_s, 3), mean_force_n=round(self.best_mean, 3),
                                    max_force_n=round(self.max_f, 3), gap_to_wall_m=round(gap, 5))


def build(cfg: PushForceConfig, d: Drawer) -> TrialSetup:
    geo, truth, place, nom = draw_box(d, "box", cfg.box)
    scene = Scene(geometry={"box": geo}, start={"box": place}, fixtures={"wall": wall_fixture(cfg.wall)})
    return TrialSetup(scene=scene, truth={"box": truth}, nominal={"box": nom}, params=dict(d.drawn))


TASK = ContactTaskDef(
    name="push-force", description="T4: push a box against a wall and hold about 5 N on it (system C)",
    instruction="Push the box against the wall and keep pressing it with a constant force of 5 N for 2 seconds.",
    config_type=PushForceConfig, build=build, scorer=ForceScorer, target="box",
    reference_method="expert-fsm",
)
