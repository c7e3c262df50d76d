"""A trial's low-level trajectory: the command in force at every control period, whoever sent it.

`TickRecorder.attach` is given the robot before the method starts (the runner's `attach` hook): it logs
`Driver.command()` before each control period the world runs, the atomic-action starts the task's
disturbance hook is told of (tabletop), and the experimenter's restarts between attempts (contact). The
result, a `Trajectory`, is what the replay policy sends back through the step-level API; saved as `.npz`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from kintsugi.core.errors import ConfigError
from kintsugi.methods.policy.drivers import driver_for

KIND = "kintsugi-trajectory"


@dataclass
class Trajectory:
    family: str
    action_names: tuple[str, ...]
    actions: np.ndarray
    """(T, A): the command in force over control period t."""
    marks: list[tuple[int, float, tuple[str, ...]]] = field(default_factory=list)
    """Tabletop: (control period, planned s, arms) of every atomic action's start."""
    restarts: list[int] = field(default_factory=list)
    """Contact: control periods before which the scene was put back (a new attempt)."""
    source: dict[str, Any] = field(default_factory=dict)
    """The source trial: key, spec, success, framework verdict, physics steps."""

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        meta = {"kind": KIND, "family": self.family, "action_names": list(self.action_names),
                "marks": [[s, p, list(a)] for s, p, a in self.marks], "restarts": self.restarts,
                "source": self.source}
        np.savez_compressed(path, actions=self.actions, meta=np.array(json.dumps(meta)))
        return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> "Trajectory":
        try:
            with np.load(path, allow_pickle=False) as f:
                meta = json.loads(str(f["meta"]))
                actions = f["actions"]
        except (OSError, KeyError, ValueError) as exc:
            raise ConfigError(f"{path} is no kintsugi trajectory file: {exc}") from None
        if meta.get("kind") != KIND:
            raise ConfigError(f"{path} holds {meta.get('kind')!r}, not a {KIND}")
        return cls(meta["family"], tuple(meta["action_names"]), actions,
                   [(int(s), float(p), tuple(a)) for s, p, a in meta["marks"]],
                   [int(s) for s in meta["restarts"]], meta["source"])


class TickRecorder:
    """Attach to a trial (`run_trial(spec, attach=rec.attach)`); then `trajectory(record)`."""

    def __init__(self) -> None:
        self.driver: Any = None
        self._actions: list[np.ndarray] = []
        self._marks: list[tuple[int, float, tuple[str, ...]]] = []
        self._restarts: list[int] = []

    def attach(self, robot: Any, log: Any = None) -> None:
        self.driver = d = driver_for(robot)
        d.record_ticks(self._actions.append)
        if hasattr(d, "record_actions"):
            d.record_actions(lambda planned, arms: self._marks.append((len(self._actions), planned, arms)))
        if hasattr(d, "record_restarts"):
            d.record_restarts(lambda: self._restarts.append(len(self._actions)))

    def trajectory(self, record: Any = None) -> Trajectory:
        if self.driver is None:
            raise ConfigError("the recorder was never attached to a robot")
        width = len(self.driver.action_names)
        actions = np.stack(self._actions) if self._actions else np.zeros((0, width))
        source = {}
        if record is not None:
            source = {"key": record.key, "task": record.task, "method": record.method, "variant": record.variant,
                      "condition": record.condition, "seed": record.seed, "success": record.success,
                      "framework_success": record.framework_success, "physics_steps": record.physics_steps,
                      "control_steps": len(actions), "error": record.error}
        return Trajectory(self.driver.family, tuple(self.driver.action_names), actions, list(self._marks),
                          list(self._restarts), source)
