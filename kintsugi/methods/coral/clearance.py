"""What the instruction forbids touching, kept clear over the whole attempt: a path constraint the verdict checks.

`without touching the grey post` (or `don't touch the post`) names fixtures or objects to keep clear of. The cost
keeps them clear as a soft term; the verdict must not trust it. At every inner tick of an attempt, each part of
every object the instruction moves (its tracked pose and known model) is measured against each thing to avoid (a
fixture's box as the scene description gives it, an object's tracked pose and known model). Closer than the
margin breaks the constraint: the running stage and the attempt fail with the reason, and the outer loop tries
again. A solid is its box turned by the tracked orientation, bounded by the prism over its footprint: the gap
between two prisms is never more than the gap between the solids, so the check errs on the strict side.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.coral.language import read_instruction
from kintsugi.methods.coral.nouns import NotUnderstood
from kintsugi.methods.coral.types import FormulationRequest
from kintsugi.worlds.contact.robot import Observation
from kintsugi.worlds.contact.world import Scene, rotate

MARGIN_M = 0.003
"""How close a tracked box may come to a thing to avoid beyond how far it can have moved unseen, m. A tracked pose
is a camera frame's, up to `perception.latency_s` + one frame period old, and the box moves while it is pushed: on
push-around (seed 2, 1026 inner ticks, `bench/bench_coral_clearance.py`) the tracked box was up to 27 mm from the
true one, and never more than 2.4 mm beyond the path the hand travelled on the table within `REACH_M` of it and
below its top over that age (0.7 mm at rest)."""

REACH_M = 0.03
"""A hand farther than this from an object's tracked box, or above it, is not pushing it: its path then moves
nothing unseen."""

_CORNERS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)


@dataclass(frozen=True)
class Prism:
    """A convex footprint (k, 2), counter-clockwise, between two heights."""

    xy: np.ndarray
    z_lo: float
    z_hi: float


def _hull(points: np.ndarray) -> np.ndarray:
    """Convex hull of (n, 2) points, counter-clockwise (monotone chain: on a box's eight corners at the inner rate it
    takes 27 us where scipy's qhull takes 105 us)."""
    pts = sorted(set(map(tuple, np.round(points, 9))))
    if len(pts) < 3:
        return np.array(pts, dtype=float)

    def half(seq: list) -> list:
        out: list = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def box_prism(pos: np.ndarray, quat: np.ndarray, half: tuple[float, float, float],
              offset: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Prism:
    """The prism over a box part of an object at a pose (its centre `offset` in the object's frame)."""
    corners = rotate(np.asarray(quat, dtype=float)[None], np.asarray(offset) + _CORNERS * np.asarray(half)) + pos
    return Prism(_hull(corners[:, :2]), float(corners[:, 2].min()), float(corners[:, 2].max()))


def fixture_prism(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Prism:
    return Prism(np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]]), lo[2], hi[2])


def _separated(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether an edge normal of either convex polygon separates them."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        pa, pb = a @ normals.T, b @ normals.T
        if np.any((pa.max(axis=0) < pb.min(axis=0)) | (pb.max(axis=0) < pa.min(axis=0))):
            return True
    return False


def _to_edges(points: np.ndarray, poly: np.ndarray) -> float:
    start, edge = poly, np.roll(poly, -1, axis=0) - poly
    rel = points[:, None, :] - start[None]
    t = np.clip(np.sum(rel * edge, axis=2) / np.maximum(np.sum(edge * edge, axis=1), 1e-18), 0.0, 1.0)
    return float(np.min(np.linalg.norm(rel - t[..., None] * edge, axis=2)))


def gap(a: Prism, b: Prism) -> float:
    """Distance between two prisms (0 when they overlap): the footprints' distance and the heights' gap."""
    dz = max(0.0, a.z_lo - b.z_hi, b.z_lo - a.z_hi)
    dxy = min(_to_edges(a.xy, b.xy), _to_edges(b.xy, a.xy)) if _separated(a.xy, b.xy) else 0.0
    return math.hypot(dxy, dz)


class KeepClear:
    """The constraint: None while every moved object keeps clear of everything to avoid, else why it broke.

    The margin per tracked party is `margin_m` plus the length of the hand's path on the table over the last
    `age_s` while it could push a moved object (how far a pushed object can have gone since the frame its pose is from).
    One instance per attempt (`fresh`)."""

    def __init__(self, known: Scene, movers: list[str], fixtures: list[str], objects: list[str],
                 margin_m: float = MARGIN_M, age_s: float = 0.15) -> None:
        self.known, self.margin, self.age = known, margin_m, age_s
        self._hand: deque[tuple[float, np.ndarray]] = deque()
        self.movers = [m for m in movers if m not in objects]
        self.fixtures = {f: fixture_prism(tuple(p - h for p, h in zip(known.fixtures[f].pos, known.fixtures[f].half)),
                                          tuple(p + h for p, h in zip(known.fixtures[f].pos, known.fixtures[f].half)))
                         for f in fixtures}
        self.objects = objects

    def _prisms(self, obs: Observation, name: str) -> list[Prism]:
        o = obs.objects[name]
        return [box_prism(o.pos, o.quat, p.half, p.pos) for p in self.known.geometry[name].parts]

    def fresh(self) -> KeepClear:
        """The same constraint with no hand path yet (a new attempt: the scene was reset)."""
        return KeepClear(self.known, self.movers, list(self.fixtures), self.objects, self.margin, self.age)

    def _unseen_m(self, obs: Observation, moved: list[Prism]) -> float:
        """The hand's path on the table over the last `age_s`, counted where its fingertips were below a moved
        object's top and within `REACH_M` of it (where they can push it)."""
        tip = np.asarray(obs.ee[:3], dtype=float).copy()
        point = Prism(tip[None, :2], float(tip[2]), float(tip[2]))
        near = any(gap(point, p) <= REACH_M and tip[2] < p.z_hi for p in moved)
        self._hand.append((obs.t, tip[:2], near))
        while len(self._hand) > 2 and self._hand[1][0] <= obs.t - self.age:
            self._hand.popleft()
        h = list(self._hand)
        return float(sum(np.linalg.norm(b[1] - a[1]) for a, b in zip(h, h[1:]) if a[2] or b[2]))

    def __call__(self, obs: Observation) -> str | None:
        moved = {m: self._prisms(obs, m) for m in self.movers}
        per = self.margin + self._unseen_m(obs, [p for ps in moved.values() for p in ps])
        others = [(f, p, 1) for f, p in self.fixtures.items()]
        others += [(n, p, 2) for n in self.objects for p in self._prisms(obs, n)]
        for m, parts in moved.items():
            for part in parts:
                for name, other, tracked in others:
                    d, margin = gap(part, other), per * tracked
                    if d < margin:
                        how = "touched" if d <= 0.0 else f"came within {d * 1000:.1f} mm of"
                        return (f"{m} {how} {name} (kept {margin * 1000:.0f} mm clear: the instruction forbids "
                                f"touching it)")
        return None

    def __bool__(self) -> bool:
        return bool(self.movers) and bool(self.fixtures or self.objects)


def keep_clear(req: FormulationRequest, known: Scene, margin_m: float = MARGIN_M, age_s: float = 0.15) -> KeepClear:
    """The constraint the instruction sets: every object it moves keeps clear of every fixture or object it
    forbids touching. Raises NotUnderstood for an instruction outside the language or a name the scene lacks."""
    steps = read_instruction(req)
    names = lambda s: [n for n in (s.obj or "").split(",") if n]  # noqa: E731
    movers = sorted({n for s in steps if not s.negated for n in names(s) if n in known.geometry})
    avoid = {n for s in steps if s.negated and s.verb == "touch" for n in names(s)}
    return KeepClear(known, movers, sorted(avoid & set(known.fixtures)), sorted(avoid & set(known.geometry)),
                     margin_m, age_s)


def guards(req: FormulationRequest, known: Scene, age_s: float = 0.15) -> tuple[KeepClear, ...]:
    """The path constraints of a trial's attempts, whatever wrote their cost (a model, memory): a verdict must
    judge every clause of the instruction, so an instruction it cannot read is refused. `age_s`: how old a
    tracked pose can be (the camera's latency and one frame period)."""
    try:
        keep = keep_clear(req, known, age_s=age_s)
    except NotUnderstood as exc:
        raise ReasoningError(f"the instruction's constraints: {exc}") from None
    return (keep,) if keep else ()


__all__ = ["MARGIN_M", "KeepClear", "Prism", "box_prism", "fixture_prism", "gap", "guards", "keep_clear"]
