"""Batched open-loop rollouts of ONE shared planning model on a persistent thread pool.

Every sample reads the same `MjModel`, so a belief written into it (a mass, a friction) is
seen by the next batch; `refresh` re-derives the quantities MuJoCo caches from masses.
This class is the interface a different backend (e.g. MJX on a GPU) would implement:
`run(data, controls) -> RolloutBatch` and `refresh()`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from kintsugi.core.errors import ConfigError, UnknownNameError

_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS
_S = mujoco.mjtState


@dataclass
class RolloutBatch:
    """Everything a cost may read, vectorized over the K samples.

    Index t holds the state after t+1 physics steps (the initial state is not repeated).
    `valid[k]` is False when sample k produced NaN/Inf or MuJoCo reset it after a divergence.
    """

    qpos: np.ndarray  # (K, T, nq)
    qvel: np.ndarray  # (K, T, nv)
    sensordata: np.ndarray  # (K, T, nsensordata)
    controls: np.ndarray  # (K, T, nu)
    dt: float
    valid: np.ndarray  # (K,) bool
    t0: float = 0.0
    sensor_slices: dict[str, slice] = field(default_factory=dict, repr=False)

    @property
    def samples(self) -> int:
        return self.qpos.shape[0]

    def sensor(self, name: str) -> np.ndarray:
        """(K, T, dim) readings of the named sensor."""
        try:
            return self.sensordata[:, :, self.sensor_slices[name]]
        except KeyError:
            known = ", ".join(sorted(self.sensor_slices)) or "(the model has no named sensors)"
            raise UnknownNameError(f"unknown sensor {name!r}; the planning model has: {known}") from None


def sensor_slices(model: mujoco.MjModel) -> dict[str, slice]:
    """Named sensors -> their slice of sensordata, resolved once."""
    out = {}
    for i in range(model.nsensor):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_SENSOR, i)
        if name:
            adr, dim = int(model.sensor_adr[i]), int(model.sensor_dim[i])
            out[name] = slice(adr, adr + dim)
    return out


def get_state(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """The full physics state of `data` (what a rollout starts from)."""
    x = np.empty(mujoco.mj_stateSize(model, _FULL))
    mujoco.mj_getState(model, data, x, _FULL)
    return x


class RolloutEngine:
    """One persistent `mujoco.rollout.Rollout` over one planning model shared by all samples."""

    def __init__(self, model: mujoco.MjModel, nthread: int | None = None) -> None:
        self.model = model
        self.nthread = max(1, nthread if nthread is not None else (os.cpu_count() or 1))
        self._pool = mj_rollout.Rollout(nthread=self.nthread)
        self._datas = [mujoco.MjData(model) for _ in range(self.nthread)]
        self._scratch = mujoco.MjData(model)
        self.sensor_slices = sensor_slices(model)
        self.nstate = mujoco.mj_stateSize(model, _FULL)
        # offsets of qpos / qvel inside a FULLPHYSICS state vector (components are ordered)
        self._qpos0 = mujoco.mj_stateSize(model, _S.mjSTATE_TIME)
        self._qvel0 = mujoco.mj_stateSize(model, _S.mjSTATE_TIME | _S.mjSTATE_QPOS)

    def close(self) -> None:
        self._pool.close()

    def refresh(self) -> None:
        """Re-derive cached constants after beliefs changed (masses, inertias) in the shared model."""
        mujoco.mj_setConst(self.model, self._scratch)

    def run(self, data: mujoco.MjData, controls: np.ndarray) -> RolloutBatch:
        """Roll out (K, T, nu) per-step controls from the state of `data` (its warm start too)."""
        return self.run_state(get_state(self.model, data), controls, warmstart=data.qacc_warmstart)

    def run_state(
        self,
        state: np.ndarray,
        controls: np.ndarray,
        *,
        warmstart: np.ndarray | None = None,
        models: Sequence[mujoco.MjModel] | None = None,
    ) -> RolloutBatch:
        """Roll out from a FULLPHYSICS state vector (one, or one per sample).

        `models`, when given, holds one model variant per sample (same sizes as the planning
        model), e.g. a parameter grid for system identification; by default every sample
        uses the shared planning model.
        """
        controls = np.ascontiguousarray(controls, dtype=float)
        if controls.ndim != 3 or controls.shape[2] != self.model.nu:
            raise ConfigError(f"controls must be (K, T, nu={self.model.nu}), got shape {controls.shape}")
        K, T, _ = controls.shape
        state = np.asarray(state, dtype=float)
        if state.shape[-1] != self.nstate:
            raise ConfigError(f"initial state has {state.shape[-1]} values; the planning model needs {self.nstate}")
        state0 = np.ascontiguousarray(np.broadcast_to(state.reshape(-1, self.nstate), (K, self.nstate)))
        warm = None
        if warmstart is not None:
            warm = np.ascontiguousarray(np.broadcast_to(np.asarray(warmstart, float).reshape(-1, self.model.nv), (K, self.model.nv)))
        if models is None:
            model_list = [self.model] * K
        else:
            model_list = list(models)
            if len(model_list) != K:
                raise ConfigError(f"{len(model_list)} model variants for {K} control sequences")
        # fresh outputs per call: a returned batch must not change under the next run
        out_state = np.empty((K, T, self.nstate))
        out_sensor = np.empty((K, T, self.model.nsensordata))
        self._pool.rollout(
            model_list, self._datas, initial_state=state0, control=controls, skip_checks=True,
            nstep=T, initial_warmstart=warm, state=out_state,
            sensordata=out_sensor if self.model.nsensordata else None,
            control_spec=int(_S.mjSTATE_CTRL),
        )
        t_expected = state0[:, 0] + T * self.model.opt.timestep
        finite = np.isfinite(out_state).all(axis=(1, 2)) & np.isfinite(out_sensor).all(axis=(1, 2))
        # MuJoCo resets a diverging simulation (time restarts): the end time gives it away
        on_time = np.abs(out_state[:, -1, 0] - t_expected) < 0.5 * self.model.opt.timestep
        nq, nv = self.model.nq, self.model.nv
        return RolloutBatch(
            qpos=out_state[:, :, self._qpos0 : self._qpos0 + nq],
            qvel=out_state[:, :, self._qvel0 : self._qvel0 + nv],
            sensordata=out_sensor,
            controls=controls,
            dt=float(self.model.opt.timestep),
            valid=finite & on_time,
            t0=float(state0[0, 0]),
            sensor_slices=self.sensor_slices,
        )
