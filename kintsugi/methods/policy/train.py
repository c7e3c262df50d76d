"""Behaviour cloning from an exported robomimic HDF5 file (`kintsugi export --format hdf5`): a `LinearPolicy`
fitted with numpy, no torch. The export's frame rate must be the control rate (`--fps` = the task's control
rate) so that the policy's steps are the dataset's frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.methods.policy.policies import LinearPolicy


def fit_hdf5(path: str | Path, keys: tuple[str, ...], bases: int = 0, ridge: float = 1e-3,
             demos: str = "success") -> LinearPolicy:
    """Fit on the demos of `mask/<demos>` (success, all, recovered, nominal); the policy runs as many steps as
    the longest demo."""
    try:
        import h5py
    except ImportError:
        raise ConfigError("training from HDF5 needs h5py: pip install 'kintsugi[export]'") from None
    with h5py.File(path, "r") as f:
        names = [n.decode() for n in f[f"mask/{demos}"][:]]
        if not names:
            raise ConfigError(f"{path}: mask/{demos} lists no demo to learn from")
        xs, ys, ts = [], [], []
        for n in names:
            g = f[f"data/{n}"]
            missing = [k for k in keys if f"obs/{k}" not in g]
            if missing:
                raise ConfigError(f"{path}: demo {n} has no observation {', '.join(missing)}; it has "
                                  f"{', '.join(sorted(g['obs']))}")
            xs.append(np.hstack([g[f"obs/{k}"][:].reshape(len(g["actions"]), -1) for k in keys]))
            ys.append(g["actions"][:])
            ts.append(np.arange(len(ys[-1])))
    steps = max(len(y) for y in ys)
    return LinearPolicy.fit(np.vstack(xs), np.vstack(ys), keys, steps, ridge, {"demos": len(names), "source": str(path)},
                            np.concatenate(ts), bases)
