"""A ground-truth scorer built from a task's goal relations, for tasks declared in one file.

`GoalScorer` judges the end of a trial on the simulator's truth (never shown to a method): each relation
(`on`, `inside`, `beside`, `left_of`, `right_of`, `upright`, `flat`, `released`, `at_rest`, `on_table`) with
the tolerances below, from the objects' true poses and their declared shapes. The method's own perceived
checks (kintsugi/methods/agentchord/domain.py) are at least as strict as these.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from kintsugi.core.config import StrictModel
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import Shape, shape_of
from kintsugi.worlds.tabletop.spec import held, upright
from kintsugi.worlds.tabletop.world import GroundTruth, TabletopWorld

ON_GAP_M = 0.015
"""`on(x, y)`: x's lowest point within this of y's highest, and x's centre over y's footprint."""
SIDE_M = (0.06, 0.28)
"""`left_of` / `right_of`: x's centre this far to y's side (world y)..."""
SIDE_ALONG_M = 0.08
"""...and within this of it front to back (world x)."""
BESIDE_M = (0.06, 0.28)
"""`beside`: the centres this far apart horizontally."""
TABLE_Z_M = 0.01
"""`on_table`: the object's lowest point within this of the table top."""

Relation = tuple[str, ...]


def _frame(truth: GroundTruth, obj: str) -> np.ndarray:
    w, x, y, z = truth.objects[obj].quat
    return Rotation.from_quat([x, y, z, w]).as_matrix()


def half_extents(shape: Shape) -> np.ndarray:
    if shape.kind == "box":
        return np.asarray(shape.half_extents, float)
    if shape.kind == "sphere":
        return np.full(3, shape.radius)
    return np.array([shape.radius, shape.radius, shape.half_height])


def lowest(truth: GroundTruth, obj: str, shape: Shape) -> float:
    """The object's lowest point (its bounding primitive's support downwards)."""
    z = float(truth.objects[obj].pos[2])
    if shape.kind == "sphere":
        return z - shape.radius
    m = _frame(truth, obj)
    if shape.kind == "box":
        return z - float(np.abs(m[2, :]) @ half_extents(shape))
    axis_z = abs(float(m[2, 2]))  # a cylinder: its caps' rims
    return z - shape.half_height * axis_z - shape.radius * float(np.sqrt(max(0.0, 1 - axis_z ** 2)))


def highest(truth: GroundTruth, obj: str, shape: Shape) -> float:
    return 2 * float(truth.objects[obj].pos[2]) - lowest(truth, obj, shape)


def over_footprint(truth: GroundTruth, obj: str, base: str, shape: Shape, margin: float = 0.0) -> bool:
    """obj's centre lies over base's footprint (in base's own frame, its half-extents less `margin`)."""
    d = _frame(truth, base).T @ (np.asarray(truth.objects[obj].pos) - np.asarray(truth.objects[base].pos))
    he = half_extents(shape)
    if shape.kind != "box":
        return bool(np.hypot(d[0], d[1]) <= he[0] - margin)
    return bool(abs(d[0]) <= he[0] - margin and abs(d[1]) <= he[1] - margin)


def rests_flat(truth: GroundTruth, obj: str, tol_deg: float) -> bool:
    """A box rests on any face (one of its axes vertical); a round object lies with its axis level or stands."""
    m = _frame(truth, obj)
    return bool(np.max(np.abs(m[2, :])) >= np.cos(np.radians(tol_deg)))


class GoalScorer:
    """Judges the goal relations at the end of the trial (watching nothing on the way)."""

    def __init__(self, cfg: TabletopConfig, relations: tuple[Relation, ...]) -> None:
        self.cfg, self.relations = cfg, relations

    def watch(self, world: TabletopWorld) -> None:
        """Only the final scene counts."""

    def judge(self, truth: GroundTruth, rel: Relation) -> bool:
        sc = self.cfg.scoring
        name, args = rel[0], rel[1:]
        shape = {o: shape_of(o, self.cfg.objects) for o in args}
        pos = {o: np.asarray(truth.objects[o].pos) for o in args}
        if name == "on":
            x, y = args
            gap = lowest(truth, x, shape[x]) - highest(truth, y, shape[y])
            return abs(gap) <= ON_GAP_M and over_footprint(truth, x, y, shape[y])
        if name == "inside":
            x, y = args
            return over_footprint(truth, x, y, shape[y]) and lowest(truth, x, shape[x]) < highest(truth, y, shape[y])
        if name in ("left_of", "right_of"):
            x, y = args
            d = pos[x] - pos[y]
            side = d[1] if name == "left_of" else -d[1]
            return bool(SIDE_M[0] <= side <= SIDE_M[1] and abs(d[0]) <= SIDE_ALONG_M)
        if name == "beside":
            x, y = args
            d = float(np.hypot(*(pos[x] - pos[y])[:2]))
            return BESIDE_M[0] <= d <= BESIDE_M[1] and lowest(truth, x, shape[x]) <= TABLE_Z_M
        (x,) = args
        if name == "upright":
            return upright(truth, x, sc.upright_tol_deg, shape[x])
        if name == "flat":
            return rests_flat(truth, x, sc.upright_tol_deg)
        if name == "on_table":
            return abs(lowest(truth, x, shape[x])) <= TABLE_Z_M
        if name == "released":
            return not held(truth, x)
        if name == "at_rest":
            return truth.objects[x].speed_m_s <= sc.rest_speed_m_s
        raise ValueError(f"the goal scorer cannot judge {name!r}")

    def finish(self, world: TabletopWorld) -> tuple[bool, "GoalDetails"]:
        truth = world.ground_truth()
        checks = {f"{r[0]}({', '.join(r[1:])})": self.judge(truth, r) for r in self.relations}
        return all(checks.values()), GoalDetails(checks=checks)


class GoalDetails(StrictModel):
    checks: dict[str, bool]
    """Each goal relation, judged on ground truth at the end."""


def goal_scorer(*relations: Relation) -> Callable[[TabletopConfig], GoalScorer]:
    """A task's `scorer`: `goal_scorer(("on", "red_block", "blue_block"), ("released", "red_block"))`."""
    return lambda cfg: GoalScorer(cfg, tuple(relations))
