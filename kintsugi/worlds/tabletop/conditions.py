"""Randomized trial conditions: seed + condition -> start poses, and the drop disturbance.

Every random value is drawn in a fixed order whatever the condition, so trial i of
`pose`, `drop` and `all` shares the same layout (paired comparison across methods
and conditions). Under `none` every object starts at the middle of its ranges.
"""

from __future__ import annotations

import math

import numpy as np

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import ConfigError
from kintsugi.worlds.tabletop.config import TabletopConfig
from kintsugi.worlds.tabletop.objects import shape_of
from kintsugi.worlds.tabletop.world import StartPose, TabletopWorld

CONDITIONS: dict[str, str] = {
    "none": "nominal layout: every object at the middle of its pose ranges, no disturbance",
    "pose": "object start poses drawn from objects.<name>.x_m / y_m / yaw_deg, no disturbance",
    "drop": "randomized poses; with probability disturbance.drop_p per atomic action the held object is "
            "released at a random instant of it",
    "shift": "randomized poses; the task's target object is slid disturbance.shift_m across the table during "
             "one of its early actions",
    "knock": "randomized poses; a standing object is pushed over (disturbance.knock_push) during an early action",
    "all": "randomized poses and every disturbance the task has (drop, shift, knock)",
}
POSE_CONDITIONS = ("pose", "drop", "shift", "knock", "all")
DROP_CONDITIONS = ("drop", "all")
SHIFT_CONDITIONS = ("shift", "all")
KNOCK_CONDITIONS = ("knock", "all")
MAX_TRIES = 200


class TrialParams(StrictModel):
    """The randomized truth of one trial (hidden from methods; recorded for analysis)."""

    start: dict[str, StartPose]
    drop_p: float = 0.0
    shift: bool = False
    knock: bool = False

    def flat(self) -> dict[str, float]:
        out: dict[str, float] = {}
        for k, p in self.start.items():
            out |= {f"{k}_x": round(p.x, 5), f"{k}_y": round(p.y, 5), f"{k}_yaw_deg": round(p.yaw_deg, 3)}
        return out | {"drop_p": self.drop_p, "shift": float(self.shift), "knock": float(self.knock)}


def _footprint(kind: str, cfg: TabletopConfig) -> float:
    s = shape_of(kind, cfg.objects)
    return s.radius if s.kind == "cylinder" else math.hypot(s.half_extents[0], s.half_extents[1])


def sample_params(cfg: TabletopConfig, objects: tuple[str, ...], condition: str, seed: int,
                  min_gap_m: float = 0.03, known: dict[str, str] = CONDITIONS) -> TrialParams:
    if condition not in known:
        raise ConfigError(f"unknown condition {condition!r}; known: {', '.join(known)}")
    rng = np.random.default_rng(seed)
    nominal = {k: StartPose(x=sum(getattr(cfg.objects, k).x_m) / 2, y=sum(getattr(cfg.objects, k).y_m) / 2,
                            yaw_deg=sum(getattr(cfg.objects, k).yaw_deg) / 2) for k in objects}
    drawn = nominal
    for _ in range(MAX_TRIES):
        cand = {}
        for k in objects:
            o = getattr(cfg.objects, k)
            cand[k] = StartPose(x=float(rng.uniform(*o.x_m)), y=float(rng.uniform(*o.y_m)),
                                yaw_deg=float(rng.uniform(*o.yaw_deg)))
        if _separated(cand, cfg, min_gap_m):
            drawn = cand
            break
    else:
        raise ConfigError(f"could not place {', '.join(objects)} apart in {MAX_TRIES} draws; widen objects.*.x_m/y_m")
    return TrialParams(start=drawn if condition in POSE_CONDITIONS else nominal,
                       drop_p=cfg.disturbance.drop_p if condition in DROP_CONDITIONS else 0.0,
                       shift=condition in SHIFT_CONDITIONS and "shift" in known,
                       knock=condition in KNOCK_CONDITIONS and "knock" in known)


def _separated(poses: dict[str, StartPose], cfg: TabletopConfig, gap: float) -> bool:
    names = list(poses)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            d = math.hypot(poses[a].x - poses[b].x, poses[a].y - poses[b].y)
            if d < _footprint(a, cfg) + _footprint(b, cfg) + gap:
                return False
    return True


class DropDisturbance:
    """With probability p per atomic action that starts with an object in hand, the held object is let go at a
    random instant of it.

    Two random numbers are drawn per such action whatever happens, so the k-th carrying action of every method
    meets the same draws. Actions that start empty-handed draw nothing: they have nothing to drop (of 150 drops
    measured when they did draw, one fell in a grasp's last instant), and their number differs between methods
    (waits for a fallen object to settle, trips home), which shifted every later draw and unpaired the trials."""

    def __init__(self, world: TabletopWorld, p: float, release_s: float, seed: int) -> None:
        self._world = world
        self.p = p
        self.release_s = release_s
        self._rng = np.random.default_rng([seed, 0xD809])
        self._pending: tuple[float, tuple[str, ...]] | None = None
        self.events: list[tuple[float, str]] = []

    def begin_action(self, planned_s: float, arms: tuple[str, ...]) -> None:
        self._pending = None
        if not any(n == 2 for arm in arms for n in self._world.pad_contacts(arm)[0].values()):
            return
        hit, when = self._rng.random(), self._rng.random()
        self._pending = (self._world.data.time + when * planned_s, arms) if hit < self.p else None

    def __call__(self, world: TabletopWorld) -> None:
        if self._pending is None or world.data.time < self._pending[0]:
            return
        _, arms = self._pending
        self._pending = None
        for arm in arms:
            held = [k for k, n in world.pad_contacts(arm)[0].items() if n == 2]
            if held:
                world.force_open(arm, self.release_s)
                self.events.append((float(world.data.time), f"{arm} gripper dropped {', '.join(held)}"))
