"""Video of a contact trial: the scene camera, with the planner's view drawn into the scene.

Overlays (added to the render's scene as visual-only geoms, never to the physics): the
current stage's contact-region candidate points (green) and the best rollout's predicted
tool-centre-point path (yellow). The planner publishes them through `show_plan`, and its per-step
statistics (cost, temperature, ESS) through `plan_step`: they become a PNG beside the video (plot.py).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from kintsugi.worlds.contact.plot import PlanSeries
from kintsugi.worlds.contact.world import EvaluationWorld
from kintsugi.core.video import VideoRecorder

PATH_RGBA = np.array([1.0, 0.85, 0.1, 0.9], dtype=np.float32)
REGION_RGBA = np.array([0.1, 0.9, 0.3, 0.9], dtype=np.float32)


class ContactVideo(VideoRecorder):
    def __init__(self, world: EvaluationWorld) -> None:
        super().__init__(scale=1)
        self._world = world
        self.path = np.zeros((0, 3))
        self.points = np.zeros((0, 3))
        self.series = PlanSeries()

    def plan_step(self, t: float, stage: str, cost: float, temperature: float, ess_frac: float) -> None:
        self.series.add(t, stage, cost, temperature, ess_frac)

    def show_plan(self, path: np.ndarray, points: np.ndarray) -> None:
        """The best rollout's predicted TCP path (T, 3) and the contact candidates (J, 3), world frame."""
        self.path, self.points = np.asarray(path), np.asarray(points)

    @property
    def data(self) -> mujoco.MjData:
        return self._world.data

    def on_tick(self, world: EvaluationWorld) -> None:  # noqa: D102 - VideoRecorder's hook
        super().on_tick(self)

    def save(self, path: str | Path) -> Path:
        """The video, and the planner's statistics as a PNG beside it (listed in `notes`)."""
        saved = super().save(path)
        self.notes: list[tuple[str, str]] = []
        if self.series.t:
            from kintsugi.worlds.contact.plot import plot_path_for, plot_plan

            plot = plot_plan(self.series, plot_path_for(str(saved)), title=Path(saved).stem)
            self.notes.append(("plot", f"planner statistics: {plot}"))
        return saved

    def render(self) -> np.ndarray:
        r = self._world.renderer()
        r.update_scene(self._world.data, camera="scene")
        scn = r.scene
        for p in self.path[:: max(1, len(self.path) // 25)]:
            _add_sphere(scn, p, 0.004, PATH_RGBA)
        for p in self.points:
            _add_sphere(scn, p, 0.005, REGION_RGBA)
        return r.render()


def _add_sphere(scn: mujoco.MjvScene, pos: np.ndarray, radius: float, rgba: np.ndarray) -> None:
    if scn.ngeom >= scn.maxgeom:
        return
    mujoco.mjv_initGeom(scn.geoms[scn.ngeom], int(mujoco.mjtGeom.mjGEOM_SPHERE), np.full(3, radius),
                        np.asarray(pos, dtype=np.float64), np.eye(3).ravel(), rgba)
    scn.ngeom += 1
