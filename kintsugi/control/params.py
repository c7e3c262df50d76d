"""Physical beliefs written into a planning model: body masses and geom sliding friction.

A mass belief scales the body's inertia with it (same shape, different density) and is
followed by `mj_setConst`, which re-derives what MuJoCo caches from masses. Friction is the
sliding coefficient only; MuJoCo resolves a contact pair's friction as the geom with the
higher `priority`, or the larger of the two when priorities are equal.
"""

from __future__ import annotations

from typing import Literal

import mujoco
import numpy as np

from kintsugi.core.errors import ConfigError, UnknownNameError

Kind = Literal["mass", "friction"]
_OBJ = {"mass": mujoco.mjtObj.mjOBJ_BODY, "friction": mujoco.mjtObj.mjOBJ_GEOM}


def resolve(model: mujoco.MjModel, kind: Kind, name: str) -> int:
    """Id of the body (mass) or geom (friction) called `name`; errors list the names that exist."""
    if kind not in _OBJ:
        raise ConfigError(f"unknown parameter kind {kind!r}; use mass or friction")
    obj = _OBJ[kind]
    i = mujoco.mj_name2id(model, obj, name)
    if i < 0:
        count = model.nbody if kind == "mass" else model.ngeom
        known = [mujoco.mj_id2name(model, obj, j) for j in range(count)]
        what = "body" if kind == "mass" else "geom"
        raise UnknownNameError(
            f"no {what} named {name!r} in the planning model; {what}s: {', '.join(n for n in known if n) or '(none named)'}"
        )
    return i


def get_param(model: mujoco.MjModel, kind: Kind, name: str) -> float:
    i = resolve(model, kind, name)
    return float(model.body_mass[i] if kind == "mass" else model.geom_friction[i, 0])


def set_param(model: mujoco.MjModel, kind: Kind, name: str, value: float) -> None:
    """Write one belief (no mj_setConst: call `commit` after a batch of writes)."""
    if not np.isfinite(value) or value <= 0:
        raise ConfigError(f"{kind} of {name!r} must be a positive number, got {value}")
    i = resolve(model, kind, name)
    if kind == "mass":
        scale = value / model.body_mass[i] if model.body_mass[i] > 0 else 1.0
        model.body_mass[i] = value
        model.body_inertia[i] *= scale
    else:
        model.geom_friction[i, 0] = value


def commit(model: mujoco.MjModel) -> None:
    """Re-derive what MuJoCo caches from masses (subtree masses, the inverse inertias contacts use)."""
    mujoco.mj_setConst(model, mujoco.MjData(model))


def pair_friction(model: mujoco.MjModel, geom_a: str, geom_b: str) -> float:
    """The sliding friction MuJoCo uses for a contact between two geoms (priority, else max)."""
    a, b = resolve(model, "friction", geom_a), resolve(model, "friction", geom_b)
    pa, pb = model.geom_priority[a], model.geom_priority[b]
    if pa != pb:
        return float(model.geom_friction[a if pa > pb else b, 0])
    return float(max(model.geom_friction[a, 0], model.geom_friction[b, 0]))
