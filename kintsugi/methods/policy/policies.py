"""Policies the `policy` method runs: observation dict -> action vector, or None when done.

A policy is any callable `policy(obs) -> np.ndarray | None`; optional attributes: `reset()` (called
before the first step), `images` (False: the observation holds no camera images, which saves the
renders), `verdict` (the policy's own claim of success, default False), `driver_options` (tabletop:
the disturbance `schedule` or `period_s`), `restarts` (contact: control steps before which the scene is
put back, as between attempts).

Built in: `ReplayPolicy` (a recorded trial's commands, step for step) and `LinearPolicy` (behaviour
cloning: ridge regression from the low-dimensional observation to the action, fitted with numpy on
exported data). `load_policy(path)` takes `module:attribute` (a policy, or a class built with no
arguments), a `.npz` file (a trajectory -> replay, a fitted linear policy -> that policy) or `file.hdf5#demo_N`
(an exported robomimic demo recorded at the control rate -> replay of its actions).
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.methods.policy.trajectory import KIND as TRAJECTORY, Trajectory

LINEAR = "kintsugi-linear-policy"


class ReplayPolicy:
    """Sends a recorded trajectory's commands back, one per control step; done after the last."""

    images = False

    def __init__(self, trajectory: Trajectory) -> None:
        self.trajectory = trajectory
        self.verdict = bool(trajectory.source.get("framework_success", False))
        self.driver_options = {"schedule": trajectory.marks} if trajectory.family == "tabletop" else {}
        self.restarts = list(trajectory.restarts)
        self._i = 0

    def reset(self) -> None:
        self._i = 0

    def __call__(self, obs: dict[str, np.ndarray]) -> np.ndarray | None:
        if self._i >= len(self.trajectory.actions):
            return None
        a = self.trajectory.actions[self._i]
        self._i += 1
        return a


def low_dim(obs: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray:
    return np.concatenate([np.asarray(obs[k], dtype=np.float64).reshape(-1) for k in keys])


def time_features(i: int | np.ndarray, steps: int, bases: int) -> np.ndarray:
    """Gaussian bumps over the policy's own clock (step i of `steps`): lets a linear map follow a trajectory's
    phases (no observation of the world in it, only the policy's count of its own steps)."""
    if bases <= 0:
        return np.zeros((np.size(i), 0))
    centres = np.linspace(0.0, 1.0, bases)
    x = np.atleast_1d(np.asarray(i, dtype=np.float64)) / max(steps, 1)
    return np.exp(-0.5 * ((x[:, None] - centres[None, :]) * (bases - 1 or 1)) ** 2)


class LinearPolicy:
    """a = W^T [x; phi(t); 1] on standardised low-dimensional observations x (no images) and `bases` time
    features phi of the policy's own step count; runs `steps` control steps."""

    images = False

    def __init__(self, keys: tuple[str, ...], mean: np.ndarray, std: np.ndarray, weights: np.ndarray,
                 steps: int, meta: dict[str, Any] | None = None, bases: int = 0) -> None:
        self.keys, self.mean, self.std, self.weights, self.steps = keys, mean, std, weights, steps
        self.bases = bases
        self.meta = meta or {}
        self._i = 0

    @classmethod
    def fit(cls, obs: np.ndarray, actions: np.ndarray, keys: tuple[str, ...], steps: int, ridge: float = 1e-3,
            meta: dict[str, Any] | None = None, step_index: np.ndarray | None = None,
            bases: int = 0) -> "LinearPolicy":
        """Least squares with an L2 penalty `ridge` on standardised features (scale-free), plus a bias;
        `step_index` (each row's step in its episode) feeds `bases` time features."""
        mean, std = obs.mean(0), obs.std(0)
        std = np.where(std > 1e-9, std, 1.0)
        phi = time_features(step_index if step_index is not None else np.zeros(len(obs)), steps, bases)
        x = np.hstack([(obs - mean) / std, phi, np.ones((len(obs), 1))])
        reg = ridge * len(obs) * np.eye(x.shape[1])
        reg[-1, -1] = 0.0
        w = np.linalg.solve(x.T @ x + reg, x.T @ actions)
        return cls(keys, mean, std, w, steps, meta, bases)

    def predict(self, x: np.ndarray, step: int | np.ndarray = 0) -> np.ndarray:
        x = np.atleast_2d(x)
        phi = time_features(np.broadcast_to(step, (len(x),)), self.steps, self.bases)
        return np.hstack([(x - self.mean) / self.std, phi, np.ones((len(x), 1))]) @ self.weights

    def reset(self) -> None:
        self._i = 0

    def __call__(self, obs: dict[str, np.ndarray]) -> np.ndarray | None:
        if self._i >= self.steps:
            return None
        self._i += 1
        return self.predict(low_dim(obs, self.keys), self._i - 1)[0]

    def save(self, path: str | Path) -> Path:
        meta = {"kind": LINEAR, "keys": list(self.keys), "steps": self.steps, "bases": self.bases, **self.meta}
        np.savez(path, mean=self.mean, std=self.std, weights=self.weights, meta=np.array(json.dumps(meta)))
        path = Path(path)
        return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")


def load_policy(path: str) -> Any:
    """A policy from `module:attribute` or a `.npz` file; a one-line ConfigError on anything else."""
    if not path:
        raise ConfigError("the policy method needs a policy: --set method.path=module:callable or a .npz file")
    if ".hdf5" in path:
        return _from_hdf5(path)
    if path.endswith(".npz"):
        p = Path(path)
        if not p.is_file():
            raise ConfigError(f"policy file {path} not found")
        with np.load(p, allow_pickle=False) as f:
            meta = json.loads(str(f["meta"])) if "meta" in f else {}
            kind = meta.get("kind")
            if kind == LINEAR:
                return LinearPolicy(tuple(meta["keys"]), f["mean"], f["std"], f["weights"], int(meta["steps"]),
                                    {k: v for k, v in meta.items() if k not in ("kind", "keys", "steps", "bases")},
                                    int(meta.get("bases", 0)))
        if kind == TRAJECTORY:
            return ReplayPolicy(Trajectory.load(p))
        raise ConfigError(f"{path} holds no kintsugi policy (kind {kind!r}; known: {TRAJECTORY}, {LINEAR})")
    module, sep, attr = path.partition(":")
    if not sep or not module or not attr:
        raise ConfigError(f"policy {path!r}: give module:attribute (e.g. my_pkg.policies:Reach) or a .npz file")
    try:
        obj = getattr(importlib.import_module(module), attr)
    except ModuleNotFoundError:
        raise ConfigError(f"policy module {module!r} not found (is it on PYTHONPATH?)") from None
    except AttributeError:
        raise ConfigError(f"module {module!r} has no attribute {attr!r}") from None
    policy = obj() if isinstance(obj, type) else obj
    if not callable(policy):
        raise ConfigError(f"policy {path!r} is not callable (a policy maps an observation dict to an action)")
    return policy


def _from_hdf5(path: str) -> ReplayPolicy:
    """`file.hdf5#demo_N`: replay the actions of one exported demo; it must have been exported at the control
    rate (one frame per control period), else its actions are not the commands of every period."""
    from kintsugi.methods.policy.trajectory import Trajectory

    file, _, demo = path.partition("#")
    if not demo:
        raise ConfigError(f"policy {path!r}: name the demo to replay, e.g. {file}#demo_0")
    try:
        import h5py
    except ImportError:
        raise ConfigError("replaying an HDF5 demo needs h5py: pip install 'kintsugi[export]'") from None
    if not Path(file).is_file():
        raise ConfigError(f"policy file {file} not found")
    with h5py.File(file, "r") as f:
        if f"data/{demo}" not in f:
            raise ConfigError(f"{file} has no {demo}; it has {', '.join(sorted(f['data']))}")
        g = f[f"data/{demo}"]
        meta = json.loads(g.attrs["kintsugi"])
        env = json.loads(f["data"].attrs["env_args"])["env_kwargs"]
        actions = g["actions"][:]
    if meta.get("every", 1) != 1:
        raise ConfigError(f"{file}#{demo} was exported at {meta.get('fps')} fps, one frame every {meta['every']} "
                          f"control periods; a replay needs every period: export with --fps {meta.get('control_hz')}")
    if "action_marks" not in meta:
        raise ConfigError(f"{file}#{demo} is in the tabletop layout (gripper open/closed, no action starts), which "
                          "cannot be replayed exactly; replay a --format trajectory export of the trial")
    marks = [(int(s), float(p), tuple(a)) for s, p, a in meta["action_marks"]]
    restarts = [int(s) for s in meta.get("restarts", [])]
    source = {"key": meta.get("key"), "success": meta.get("success"), "framework_success": meta.get("framework_success")}
    return ReplayPolicy(Trajectory(env.get("family", "tabletop"), tuple(env.get("action_names", ())), actions, marks,
                                   restarts, source))
