"""System identification of an object's mass and friction from the robot's own log of an attempt.

The log (observations + commands at the inner rate) is cut into short windows where the
object moved or the wrist felt a force. Each window is replayed open-loop in planning-model
variants from the state the robot observed at its start (proprioception + tracked pose and
velocity), and compared with what the tracker and the F/T sensor saw next (multiple
shooting: short windows keep contact-rich replays from drifting apart). The fit itself is
`kintsugi.control.sysid.fit` (batched grids, then Nelder-Mead). Ground truth never enters.
"""

from __future__ import annotations

import numpy as np

from kintsugi.control.rollout import get_state
from kintsugi.control.sysid import ExecutionLog as ReplayLog
from kintsugi.control.sysid import ParamSpec, Signal, SysIdConfig, SysIdProblem, SysIdResult, fit, replay_loss
from kintsugi.core.errors import ConfigError
from kintsugi.worlds.contact.objects import Physics
from kintsugi.worlds.contact.robot import ExecutionLog, Observation
from kintsugi.worlds.contact.world import PlanningWorld

WINDOW_TICKS = 30
MAX_WINDOWS = 24
"""Windows taken from one attempt."""
FIT_WINDOWS = 16
"""Windows one fit replays, over every attempt so far (sliding ones first, the rest evenly spread): a fit's
cost is the windows times the grid, so it stays bounded however many attempts the trial has had."""
MOVING_M_S = 0.01
WINDOW_CAP = 1.0
"""A window's loss counts in full up to 1 (binned residuals of 5 mm / 1 N rms), then barely: a push where
the fingertips drag on the table replays stick-slip differently on a 1 % change of any parameter, and its
loss (2-8) would otherwise decide the fit (T1: friction 0.20 fitted for a true 0.37)."""
FORCE_N = 0.5
MIN_FELT = 8
"""Windows kept for the weight (lifting, carrying) however many sliding windows there are."""
ON_TABLE_M = 0.004
"""The object counts as resting on the table while its tracked height stays this close to its start."""
PINCH_N = 0.5
PINCH_OPENING_M = 0.003
"""Both finger pads feel at least PINCH_N with the fingers apart: the object is in the pinch (closed fingers
press their pads on each other)."""
TABLE_TOUCH_M = 0.002
GRIND_N = 3.0
"""Fingertips this close to the table top while the wrist pushes down harder than this: grinding on it."""
MIN_GAIN = 0.05
"""A fit is adopted only when it lowers the replay loss by more than this (binned residual units: 5 mm / 1 N)..."""
MIN_GAIN_FRACTION = 0.1
"""...and by more than this fraction of the prior's loss: a smaller gain is the replay's own noise."""


def raw_ft(obs: Observation, hand_weight_n: float) -> np.ndarray:
    """Undo the robot's taring: the F/T reading in the hand frame, as the planning model's sensor gives it."""
    f = obs.force + np.array([0.0, 0.0, hand_weight_n])
    c, s = np.cos(obs.ee[3]), np.sin(obs.ee[3])
    return np.array([c * f[0] + s * f[1], -s * f[0] + c * f[1], f[2]])


def _kind(seg: list[Observation], obj: str, rest_z: float) -> str | None:
    """What a window of the log can tell, from the robot's own readings (None: nothing).

    - "slide": the object moved while resting on the table (its height as at the start): its friction
      against the table is in the push force and the motion;
    - "grind": as "slide" or "felt", but the fingertips were down on the table top pressing on it: the
      pads' drag on the table (their friction is high, and it flips between stick and slip) swamps the
      object's own friction force, and no replay follows it; such a window is left out;
    - "lift": the object moved off the table (lifted, carried): its weight hangs on the hand, so its mass is in
      the wrist's force;
    - "felt": the wrist felt a force, or the object moved in the pinch of both pads (the pads' grip, not the
      table, then sets how it moves): kept for the fit, but it tells neither parameter apart on its own.
    """
    moving = max(np.linalg.norm(o.objects[obj].lin_vel) for o in seg) > MOVING_M_S
    pressed = max(np.linalg.norm(o.force) for o in seg) > FORCE_N
    if not (moving or pressed):
        return None
    grinding = any(o.ee[2] < TABLE_TOUCH_M and -o.force[2] > GRIND_N for o in seg)
    on_table = all(abs(o.objects[obj].pos[2] - rest_z) < ON_TABLE_M for o in seg)
    if grinding and on_table:
        return "grind"
    pinched = any(o.touch.min() > PINCH_N and o.opening > PINCH_OPENING_M for o in seg)
    if moving and on_table and not pinched:
        return "slide"
    return "lift" if not on_table else "felt"


def windows(planning: PlanningWorld, log: ExecutionLog, obj: str, ticks: int = WINDOW_TICKS) -> list[ReplayLog]:
    """Informative windows of one attempt as replay logs (states are planning-model states).

    Every sliding window is kept (up to `MAX_WINDOWS` - `MIN_FELT`): they are the few that carry the
    friction, and even thinning among all windows dropped half of them for the many windows of a
    carried object. The rest of the budget goes to the other windows, evenly spread over the attempt."""
    n = len(log.obs) - 1
    if n < ticks:
        return []
    hw = planning.layout.hand_weight_n
    dt = float(np.median(np.diff([o.t for o in log.obs])))
    rest_z = float(log.obs[0].objects[obj].pos[2])
    picked: dict[str, list[int]] = {"slide": [], "felt": []}
    label: dict[int, str] = {}
    for i in range(0, n - ticks + 1, ticks):
        kind = _kind(log.obs[i:i + ticks + 1], obj, rest_z)
        if kind in ("slide", "felt", "lift"):
            picked["slide" if kind == "slide" else "felt"].append(i)
            label[i] = kind
    slides = _thinned(picked["slide"], MAX_WINDOWS - min(MIN_FELT, len(picked["felt"])))
    kinds = {i: label[i] for i in _thinned(picked["felt"], MAX_WINDOWS - len(slides))} | {i: "slide" for i in slides}
    out: list[ReplayLog] = []
    for i, kind in sorted(kinds.items()):
        seg = log.obs[i:i + ticks + 1]
        start = seg[0]
        data = planning.sync(start.ee, start.ee_vel, start.fingers, start.finger_vel,
                             {k: (o.pos, o.quat, o.lin_vel, o.ang_vel) for k, o in start.objects.items()},
                             start.ctrl, start.t)
        out.append(ReplayLog(
            initial_state=get_state(planning.model, data), controls=np.array(log.ctrl[i:i + ticks]),
            observed={f"{obj}_pos": np.array([o.objects[obj].pos for o in seg[1:]]),
                      "ft_force": np.array([raw_ft(o, hw) for o in seg[1:]])},
            dt=dt, label=kind))
    return out


def _thinned(starts: list[int], keep: int) -> list[int]:
    """At most `keep` of the window starts, evenly spread (bounded cost, the whole attempt still covered)."""
    if keep <= 0:
        return []
    if len(starts) <= keep:
        return starts
    return [starts[k] for k in np.linspace(0, len(starts) - 1, keep).round().astype(int)]


class BeliefFitter:
    """Collects windows over attempts and refits one object's mass and friction against the table."""

    def __init__(self, planning: PlanningWorld, obj: str, mass_bounds: tuple[float, float],
                 friction_bounds: tuple[float, float], cfg: SysIdConfig | None = None) -> None:
        """Replays integrate at the configured simulation timestep (`sim.timestep_s`, a setting the user
        gave, not a hidden truth): the logged 10 ms commands are each held for several fine steps."""
        geoms = planning.layout.obj_geoms[obj]
        import mujoco

        names = [mujoco.mj_id2name(planning.model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) for g in geoms]
        self.geom = names[0]
        self.planning, self.obj = planning, obj
        # one friction for every box of the object (a board's plate and handle both slide on the table)
        self.params = [ParamSpec(kind="mass", name=obj, bounds=mass_bounds),
                       ParamSpec(kind="friction", name=self.geom, bounds=friction_bounds, against="table",
                                 also=tuple(names[1:]))]
        self.signals = [Signal(sensor=f"{obj}_pos", scale=0.005, bin=5), Signal(sensor="ft_force", scale=1.0, bin=5)]
        sim = planning.cfg.sim
        substeps = max(1, round(sim.planning_timestep_s / sim.timestep_s))
        self.cfg = cfg or SysIdConfig(grid=7, zoom_rounds=2, max_evals=24, substeps=substeps, window_cap=WINDOW_CAP)
        self.logs: list[ReplayLog] = []
        self.kept: str | None = None
        """Why the last fit was not adopted (None: it was)."""

    def chosen(self) -> list[ReplayLog]:
        """The windows a fit replays: at most `FIT_WINDOWS` of all so far, every sliding one first (they alone
        carry the friction), the others evenly spread over the attempts."""
        slides = [i for i, w in enumerate(self.logs) if w.label == "slide"]
        others = [i for i, w in enumerate(self.logs) if w.label != "slide"]
        keep = _thinned(slides, FIT_WINDOWS - min(MIN_FELT // 2, len(others)))
        keep += _thinned(others, FIT_WINDOWS - len(keep))
        return [self.logs[i] for i in sorted(keep)]

    def add(self, log: ExecutionLog) -> int:
        new = windows(self.planning, log, self.obj)
        self.logs += new
        return len(new)

    @property
    def slid(self) -> bool:
        """Whether any window so far saw the object slide on the table: without one, its friction against
        the table left no trace (a lift or a grinding push does not show it), so the fit keeps the belief
        rather than report whatever a flat loss happens to favour."""
        return any(w.label == "slide" for w in self.logs)

    @property
    def weighed(self) -> bool:
        """Whether any window so far saw the object slide or hang from the hand: only then does its mass leave a
        trace (a press against a wall or a touch does not move it, and any mass replays it alike)."""
        return any(w.label in ("slide", "lift") for w in self.logs)

    def story(self, added: int, phys: Physics, result: SysIdResult) -> str:
        """One line for the trial's events: what the last fit saw and found, or why the belief was kept."""
        if self.kept:
            return (f"{added} new windows ({len(self.logs)} in all): {self.obj} kept at mass {phys.mass_kg:.3f} kg, "
                    f"friction {phys.friction:.3f}: {self.kept}")
        return (f"{added} new windows ({len(self.logs)} in all): {self.obj} mass {phys.mass_kg:.3f} kg, friction "
                f"{phys.friction:.3f} (loss {result.prior_loss:.3g} -> {result.loss:.3g})"
                + ("" if self.slid else "; friction kept: the object never slid on the table"))

    def fit(self) -> tuple[Physics, SysIdResult]:
        """Fit on every window so far and, when the fit is identifiable, write it into the planning world (all the
        object's geoms). The friction is fitted only once the object has slid (`slid`), the mass only once it
        slid or hung from the hand (`weighed`); the fit is adopted only when it lowers the replay loss beyond
        noise (`MIN_GAIN`, `MIN_GAIN_FRACTION`). Otherwise the belief is kept and `kept` says why."""
        if not self.logs:
            raise ConfigError(f"no informative window in the log: {self.obj!r} never moved and nothing was felt")
        belief = self.planning.physics_of(self.obj)
        params = self.params if self.slid else self.params[:1]
        problem = SysIdProblem(self.planning.model, params, self.signals, self.chosen(), self.cfg)
        if not self.weighed:  # nothing to search: any mass replays the log alike
            self.kept = "the object never slid or hung from the hand, so the log cannot tell its mass"
            loss = replay_loss(problem)
            values = {f"mass:{self.obj}": belief.mass_kg}
            return belief, SysIdResult(params=values, prior=dict(values), loss=loss, prior_loss=loss)
        result = fit(problem)
        gain = result.prior_loss - result.loss
        self.kept = None
        if not gain > max(MIN_GAIN, MIN_GAIN_FRACTION * result.prior_loss):
            self.kept = (f"the fit lowers the replay loss by {gain:.3g} ({result.prior_loss:.3g} -> {result.loss:.3g}), "
                         "within the replay's noise")
        if self.kept:
            self.planning.set_beliefs({self.obj: belief})
            return belief, result
        phys = Physics(mass_kg=result.params[f"mass:{self.obj}"],
                       friction=result.params.get(f"friction:{self.geom}", belief.friction))
        self.planning.set_beliefs({self.obj: phys})
        return phys, result
