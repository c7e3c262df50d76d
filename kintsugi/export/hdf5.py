"""robomimic's HDF5 layout: data/demo_N/{obs, next_obs, actions, rewards, dones}, attrs as JSON, mask/ groups.

One file, `demo.hdf5`:
- `data` attrs: `total` (frames over all demos), `env_args` (JSON: env_name, type, env_kwargs with the
  task, the fps and the resolved tabletop config), `label_vocab` (JSON: edge and action names);
- `data/demo_N`: attrs `num_samples`, `model_file` is not written (the MJCF is built per trial), `kintsugi`
  (JSON: trial key, spec, recovered, success, control steps); datasets `actions` (T, 14), `rewards` (T,)
  (1 on the last frame of a successful trial), `dones` (T,), `obs/<key>` and `next_obs/<key>` (low-dim keys
  `<arm>_<key>` and `<camera>_image` (T, H, W, 3) uint8), `labels/{recovery, edge, action, action_number}`;
- `mask/{all, recovered, nominal, success}`: demo names, for robomimic's filter keys.
No `states` dataset: simulator states are ground truth, and the export holds only what the robot observed.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from kintsugi.export.recorder import ACTION_NAMES, Episode

FILE = "demo.hdf5"
ENV_TYPE = "kintsugi-tabletop"
"""robomimic's env `type` is an int for its own simulators; ours is named so no robomimic env is assumed."""


def _h5py() -> Any:
    try:
        import h5py
    except ImportError:
        from kintsugi.core.errors import ConfigError

        raise ConfigError("--format hdf5 needs h5py: pip install 'kintsugi[export]'") from None
    return h5py


class Vocab:
    """Names -> small ints, in order of first sight (written once the last episode is in)."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self._index: dict[str, int] = {}

    def ids(self, names: list[str]) -> np.ndarray:
        for n in names:
            if n not in self._index:
                self._index[n] = len(self.names)
                self.names.append(n)
        return np.asarray([self._index[n] for n in names], dtype=np.int64)


class Hdf5Writer:
    def __init__(self, out_dir: Path, source: dict[str, Any]) -> None:
        self.path = Path(out_dir) / FILE
        self._file = _h5py().File(self.path, "w")
        self._data = self._file.create_group("data")
        self._source = source
        self.edges, self.actions = Vocab(), Vocab()
        self._demos: list[tuple[str, Episode]] = []
        self._total = 0
        self._env_kwargs: dict[str, Any] | None = None

    def add(self, ep: Episode) -> None:
        name = f"demo_{len(self._demos)}"
        g = self._data.create_group(name)
        t = ep.length
        g.attrs["num_samples"] = t
        g.attrs["kintsugi"] = json.dumps({"key": ep.key, "success": ep.success, "fps": ep.fps, "every": ep.every,
                                          "control_steps": ep.control_steps, **ep.meta})
        g.create_dataset("actions", data=ep.actions)
        rewards = np.zeros(t)
        dones = np.zeros(t, dtype=np.int64)
        dones[-1] = 1
        rewards[-1] = 1.0 if ep.success else 0.0
        g.create_dataset("rewards", data=rewards)
        g.create_dataset("dones", data=dones)
        for group, rows in (("obs", slice(0, t)), ("next_obs", slice(1, t + 1))):
            og = g.create_group(group)
            for k, v in ep.obs.items():
                og.create_dataset(k, data=v[rows])
            for cam, frames in ep.images.items():
                og.create_dataset(f"{cam}_image", data=frames[rows], chunks=(1, *frames.shape[1:]),
                                  compression="gzip", compression_opts=4)
        lg = g.create_group("labels")
        lg.create_dataset("recovery", data=ep.recovery.astype(np.uint8))
        lg.create_dataset("edge", data=self.edges.ids(ep.edge))
        lg.create_dataset("action", data=self.actions.ids(ep.action))
        lg.create_dataset("action_number", data=ep.action_number)
        self._demos.append((name, ep))
        self._total += t
        if self._env_kwargs is None:
            self._env_kwargs = {"task": ep.task, "instruction": ep.instruction, "fps": ep.fps,
                                "control_hz": ep.meta.get("control_hz"), "cameras": list(ep.images),
                                "action_names": ep.meta.get("action_names", list(ACTION_NAMES)),
                                "family": ep.meta.get("family", "tabletop"), "config": ep.meta.get("config")}

    def close(self) -> Path:
        d = self._data
        d.attrs["total"] = self._total
        env_type = f"kintsugi-{self._source['system']}" if "system" in self._source else ENV_TYPE
        d.attrs["env_args"] = json.dumps({"env_name": self._source.get("task", ""), "type": env_type,
                                          "env_kwargs": self._env_kwargs or {}})
        d.attrs["label_vocab"] = json.dumps({"segment": ["nominal", "recovery"], "edge": self.edges.names,
                                             "action": self.actions.names})
        d.attrs["source"] = json.dumps(self._source)
        mask = self._file.create_group("mask")
        sets = {"all": [n for n, _ in self._demos],
                "recovered": [n for n, e in self._demos if e.recovery.any()],
                "nominal": [n for n, e in self._demos if not e.recovery.any()],
                "success": [n for n, e in self._demos if e.success]}
        for k, names in sets.items():
            mask.create_dataset(k, data=np.array(names, dtype="S"))
        self._file.close()
        return self.path

    def abort(self) -> None:
        self._file.close()
