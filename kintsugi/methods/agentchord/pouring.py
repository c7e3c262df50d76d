"""A pour judged from what the cameras see: the held object's perceived tilt, its mouth over the container.

A sub-goal with a `tilted` constraint on an object that its `over` constraints put above a container is a pour.
When a nominal edge reaches it, the conductor reads the tilt (from the object's known top, as the checks do)
and, if the turn fell short of `POUR_VERDICT_DEG` (a bottle that sat a little tilted in the hand, a grasp that
slipped), turns the hand further by the shortfall, at most `TOP_UPS` times; if the mouth is not over the
container (it was slid away while the object was carried there), the hand moves over it, at most `RE_AIMS`
times. The pour counts only when the tilt
reached `POUR_VERDICT_DEG` with the mouth (the lower end of the object's axis) above the container's perceived
opening; the goal check refuses a verdict of success while a pour it passed through was not seen done.
`POUR_VERDICT_DEG` is stricter than the scorer's 80 degrees by the tilt perception's error on a held bottle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from kintsugi.taskgraph.geometry import top_tilt_deg

POUR_VERDICT_DEG = 83.0
TOP_UP_MARGIN_DEG = 4.0
MAX_TOP_UP_DEG = 30.0
TOP_UPS = 2
RE_AIMS = 2
MAX_RE_AIM_M = 0.15
RIM_INSET_M = 0.008
"""The mouth must be this far inside the container's perceived outer radius (about a wall and a margin)."""


@dataclass(frozen=True)
class Pour:
    obj: str
    container: str


def pour_of(graph: Any, edge: Any) -> Pour | None:
    """The pour the edge's target sub-goal asks for: its `tilted` object and the container an `above` constraint
    (`over`) puts it over, on the edge's source node or else on any sub-goal of the graph."""
    tilted = [c.object for c in graph.node(edge.target).constraints if c.kind == "tilted"]
    if not tilted:
        return None
    for node in [graph.node(edge.source), *graph.nodes]:
        for c in node.constraints:
            if c.kind == "above" and c.a.entity == tilted[0] and c.b.entity != tilted[0]:
                return Pour(tilted[0], c.b.entity)
    return None


def mouth(f: Any, top: Any = None) -> np.ndarray | None:
    """The object's top end: the end of its perceived axis towards the tracked top, else its seen cap, else the
    lower end of the axis (a bottle turned past the horizontal pours from its lower end)."""
    ex = getattr(f, "extremes", None) or {}
    ends = {k: np.asarray(ex[k], float) for k in ("axis_pos", "axis_neg") if k in ex}
    if top is not None and len(ends) == 2 and getattr(f, "axis", None) is not None:
        return ends["axis_pos"] if float(np.dot(f.axis, top)) >= 0.0 else ends["axis_neg"]
    if "cap" in ex:
        return np.asarray(ex["cap"], float)
    return min(ends.values(), key=lambda p: float(p[2])) if ends else None


def signed_tilt(f: Any, top: Any) -> float:
    """The tilt of the object's top from vertical, 0-180 degrees: the perceived axis signed towards the top the
    robot tracks (its encoders while it holds the object), else as the checks read it. Near the horizontal, a
    seen cap's height says little about which end is lower (the cameras see its upper face)."""
    if top is None:
        return top_tilt_deg(f, (0.0, 0.0, -1.0))
    a = np.asarray(f.axis, float) / max(float(np.linalg.norm(f.axis)), 1e-12)
    if float(a @ np.asarray(top, float)) < 0.0:
        a = -a
    return float(np.degrees(np.arccos(np.clip(a[2], -1.0, 1.0))))


def judge(pour: Pour, objects: dict[str, Any], top: Any = None) -> tuple[float, bool, str]:
    """(perceived tilt in degrees, mouth over the opening, a one-line account); `top`: the tracked top direction."""
    f, box = objects.get(pour.obj), objects.get(pour.container)
    if f is None or box is None or getattr(f, "axis", None) is None or getattr(box, "centroid", None) is None:
        return float("nan"), False, f"{pour.obj} or {pour.container} not seen"
    tilt = signed_tilt(f, top)
    m = mouth(f, top)
    extent = getattr(box, "extent", None) or (0.0, 0.0, 0.0)
    radius = max(float(min(extent[1:] if len(extent) > 2 else extent)) / 2.0 - RIM_INSET_M, 0.0)
    top = (getattr(box, "extremes", None) or {}).get("top")
    c = np.asarray(box.centroid, float)
    if m is None or top is None:
        return tilt, False, f"{pour.obj}'s mouth or {pour.container}'s rim not seen"
    off = float(np.hypot(m[0] - c[0], m[1] - c[1]))
    over = off <= radius and float(m[2]) > float(top[2])
    return tilt, over, (f"{pour.obj} tilted {tilt:.1f} deg, mouth {off * 100:.1f} cm from {pour.container}'s axis "
                        f"(opening {radius * 100:.1f} cm), {float(m[2]) - float(top[2]):+.3f} m over its rim")


class Pouring:
    """The conductor's pour check (a mixin of `Conductor`: it acts through `_execute`, reads through `_read`)."""

    graph: Any
    robot: Any
    log: Any

    def verify_pour(self, edge: Any) -> None:
        """After a nominal edge into a pour sub-goal: top the turn up if short, then record whether it poured."""
        pour = pour_of(self.graph, edge)
        if pour is None:
            return
        turns = [a for a in edge.actions if a.name == "rotate_eef"]
        tilt, over, why = judge(pour, self._read({pour.obj, pour.container}).objects, self.tops.world.get(pour.obj))
        for _ in range(TOP_UPS if turns else 0):
            if tilt == tilt and tilt >= POUR_VERDICT_DEG:
                break
            short = POUR_VERDICT_DEG + TOP_UP_MARGIN_DEG - (tilt if tilt == tilt else POUR_VERDICT_DEG)
            angle = turns[-1].args.get("angle_deg")
            sign = -1.0 if isinstance(angle, (int, float)) and angle < 0 else 1.0
            self.log.event(self.robot.sim_time, "pour short", f"{why}: turning {min(short, MAX_TOP_UP_DEG):.1f} deg more")
            self._execute(edge, "rotate_eef", {**turns[-1].args, "angle_deg": round(sign * min(short, MAX_TOP_UP_DEG), 2)},
                          unplanned_ok=True)
            tilt, over, why = judge(pour, self._read({pour.obj, pour.container}).objects, self.tops.world.get(pour.obj))
        for _ in range(RE_AIMS if turns else 0):  # the container moved (slid by a hand) while the bottle was carried
            if over or not tilt == tilt or tilt < POUR_VERDICT_DEG:
                break
            shift = self.aim_shift(pour)
            if shift is None:
                break
            self.log.event(self.robot.sim_time, "pour re-aimed", f"{why}: moving the hand "
                           f"{np.round(shift * 100, 1).tolist()} cm over {pour.container}")
            self._execute(edge, "move_by_offset", {"arm": turns[-1].args["arm"], "dxyz": [float(shift[0]),
                          float(shift[1]), 0.0]}, unplanned_ok=True)
            tilt, over, why = judge(pour, self._read({pour.obj, pour.container}).objects, self.tops.world.get(pour.obj))
        done = tilt == tilt and tilt >= POUR_VERDICT_DEG and over
        self.pours[(pour.obj, pour.container)] = self.pours.get((pour.obj, pour.container), False) or done
        if not done:
            self.log.event(self.robot.sim_time, "pour not seen", why)

    def aim_shift(self, pour: Pour) -> np.ndarray | None:
        """The horizontal move that puts the seen mouth over the container's seen centre (None: not seen, or
        farther than MAX_RE_AIM_M, which is no slide a pour should follow)."""
        objs = self._read({pour.obj, pour.container}).objects
        f, box = objs.get(pour.obj), objs.get(pour.container)
        m = mouth(f, self.tops.world.get(pour.obj)) if f is not None and getattr(f, "axis", None) is not None else None
        if m is None or box is None or getattr(box, "centroid", None) is None:
            return None
        d = np.asarray(box.centroid[:2], float) - m[:2]
        return d if float(np.linalg.norm(d)) <= MAX_RE_AIM_M else None

    def pours_done(self) -> bool:
        """Every pour the trial passed through was seen done (tilt and mouth over the opening)."""
        missing = [f"{o} into {c}" for (o, c), ok in self.pours.items() if not ok]
        if missing:
            self.log.event(self.robot.sim_time, "goal check", f"pour not seen done: {', '.join(missing)}")
        return not missing
