"""Goal-conditioned skills, one per contact formation (CF0..CF4).

Each skill moves the wrist base in position control at bounded speed toward a
goal on its own axes ("—" axes keep the previous goal), and ends at the goal
(after a short settle), on a timeout, or at once when the wrist's z spring
passes the compression limit. Approach, the one skill that may be asked to leave
the hole (as a recovery re-approach), first rises straight up when its goal is
higher, so it never drags the peg sideways out of the hole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from kintsugi.worlds.peg.world import PegWorld

AXES = ("y", "z", "roll")
HALT_SLACK = 0.0005  # m of extra compression tolerated when a skill starts already past the limit


@dataclass(frozen=True)
class SkillSpec:
    name: str
    cf: int
    axes: tuple[str, ...]
    description: str


SKILLS: dict[str, SkillSpec] = {
    s.name: s
    for s in (
        SkillSpec("approach", 0, ("y", "z", "roll"), "move close above the board, no contact"),
        SkillSpec("contact", 1, ("z",), "go straight down until the peg touches the surface"),
        SkillSpec("fit", 2, ("y",), "slide until the peg's tip drops in and touches the hole's edge"),
        SkillSpec("align", 3, ("y",), "translate so the compliant wrist rotates the peg upright"),
        SkillSpec("insert", 4, ("z",), "push the peg down into the hole"),
    )
}
SEQUENCE = tuple(SKILLS)


@dataclass
class SkillResult:
    skill: str
    goal: np.ndarray  # full [y, z, roll] goal (m, rad)
    terminal: np.ndarray  # base pose at the end
    reached: bool
    timed_out: bool
    compression_limit: bool
    compression: float  # z-spring compression at the end (m)
    max_compression: float
    image: np.ndarray = field(repr=False)
    sim_time: float = 0.0


def execute_skill(
    world: PegWorld,
    skill: str,
    goal: np.ndarray,
    on_tick: Callable[[PegWorld], None] | None = None,
) -> SkillResult:
    """Drive the base toward `goal`; return terminal pose, image and flags."""
    ctl = world.cfg.control
    dt = 1.0 / ctl.rate_hz
    n_sub = max(1, round(dt / world.model.opt.timestep))
    dt = n_sub * world.model.opt.timestep
    v_lin = ctl.speed_mm_s * 1e-3 * dt
    v_rot = math.radians(ctl.rot_speed_deg_s) * dt
    tol = ctl.pose_tol_mm * 1e-3
    limit = ctl.compression_limit_mm * 1e-3
    t0 = world.data.time
    pose = world.base_pose()
    legs = _legs(skill, pose, goal)
    reached = halted = False
    settle_left = ctl.settle_s
    max_comp = 0.0
    # Starting beyond the limit (after a halt), a skill may still move as long as it does not
    # compress the wrist further; otherwise no recovery could ever relieve a halted wrist.
    halt_at = max(limit, world.wrist_compression() + HALT_SLACK)
    while True:
        elapsed = world.data.time - t0
        if elapsed >= ctl.timeout_s:
            break
        if not reached:
            pose = _step_toward(pose, legs[0], v_lin, v_rot)
            world.set_base(pose)
            if np.all(pose == legs[0]):
                legs.pop(0)
            reached = not legs
        world.step(n_sub)
        comp = world.wrist_compression()
        max_comp = max(max_comp, comp)
        if on_tick is not None:
            on_tick(world)
        if comp > halt_at:
            halted = True
            break
        if reached:
            settle_left -= dt
            if settle_left <= 0 and (world.wrist_is_still() or settle_left <= ctl.settle_s - ctl.settle_max_s):
                break
    terminal = world.base_pose()
    err = np.abs(terminal - goal)
    ok = bool(np.hypot(err[0], err[1]) <= tol and err[2] <= math.radians(1.0))
    return SkillResult(
        skill=skill, goal=goal.copy(), terminal=terminal, reached=ok and not halted,
        timed_out=not reached and not halted, compression_limit=halted,
        compression=world.wrist_compression(), max_compression=max_comp,
        image=world.render(), sim_time=world.data.time - t0,
    )


def _legs(skill: str, pose: np.ndarray, goal: np.ndarray) -> list[np.ndarray]:
    """Straight to the goal, except an approach to a higher goal: straight up (same roll) first."""
    if skill == "approach" and goal[1] > pose[1] and (goal[0] != pose[0] or goal[2] != pose[2]):
        return [np.array((pose[0], goal[1], pose[2])), goal.copy()]
    return [goal.copy()]


def _step_toward(pose: np.ndarray, goal: np.ndarray, v_lin: float, v_rot: float) -> np.ndarray:
    """One bounded-speed step along the straight line to the goal (exact arrival).

    Plain float math: this runs every control tick and numpy on 3-vectors costs more than the physics.
    """
    y, z, r = float(pose[0]), float(pose[1]), float(pose[2])
    gy, gz, gr = float(goal[0]), float(goal[1]), float(goal[2])
    dist = math.hypot(gy - y, gz - z)
    if dist <= v_lin:
        y, z = gy, gz
    else:
        y, z = y + (gy - y) * v_lin / dist, z + (gz - z) * v_lin / dist
    r = gr if abs(gr - r) <= v_rot else r + math.copysign(v_rot, gr - r)
    return np.array((y, z, r))
