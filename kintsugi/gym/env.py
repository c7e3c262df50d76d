"""A Gymnasium environment over any registered task: the task's own episode, stepped by its driver.

`KintsugiEnv(task, condition=..., variant=..., overrides=..., images=True, reward="sparse")` builds, at each
`reset(seed=s)`, the episode a campaign's trial with seed `s` gets (the same draws: layout, physics,
disturbances), and steps it one control period per `step(action)` through the step-level driver
(`kintsugi.methods.policy.drivers`): no second copy of any physics or scoring.

- observation: a `Dict` of the robot's sensors (and camera images, uint8, unless `images=False`), as
  the family's driver documents them; tabletop `perceived=True` adds the robot's perceived object features;
- action: the family's low-level command (`Box` with the driver's bounds);
- reward: 1.0 on the step the task's scorer first judges the trial a success (sparse); with
  `reward="shaped"` also minus `shaped_scale` x the action's change since the last step (a smoothness
  term that needs no ground truth);
- `terminated` on success, or when the physics diverges (an unrecoverable state: `info["error"]`);
  `truncated` after `max_seconds` of sim time;
- `info`: the record's common fields (task, condition, seed, success, sim_time, physics_steps, steps)
  and the drawn `params` at reset.
The scorer is asked every `score_every_s` of sim time (1 s) and on the last step: the last step's verdict is the
one a campaign's record gets for the same trajectory; the ones between only end a successful episode early (at
most `score_every_s` after the success). A task's scorer judges the whole scene from ground truth (0.1-0.5 ms), so
asking it at the control rate would cost more than the physics; a smaller `score_every_s` trades speed for a
sooner end.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from kintsugi.core.errors import KintsugiError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.methods.policy.drivers import Driver, driver_for

SEED_SPACE = 2**31 - 1


def _space(feature: Any) -> spaces.Box:
    if feature.image:
        return spaces.Box(0, 255, feature.shape, dtype=np.uint8)
    return spaces.Box(feature.low, feature.high, feature.shape, dtype=np.float64)


class KintsugiEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, task: str, condition: str | None = None, variant: str | None = None,
                 overrides: dict[str, Any] | None = None, images: bool = True, reward: str = "sparse",
                 shaped_scale: float = 0.01, max_seconds: float | None = None, score_every_s: float = 1.0,
                 period_s: float = 2.0, perceived: bool = False, render_mode: str | None = None) -> None:
        load_builtins()
        self.task = TASKS.get(task).factory()
        self.task_name = task
        self.condition = condition or self.task.default_conditions[0]
        if self.condition not in self.task.conditions:
            raise KintsugiError(f"unknown condition {self.condition!r} for {task}; known: "
                                f"{', '.join(self.task.conditions)}")
        self.variant = variant or self.task.default_variants[0]
        self.cfg = self.task.config(dict(overrides or {}))
        self.task.check_variant(self.variant, self.cfg)
        if reward not in ("sparse", "shaped"):
            raise KintsugiError(f"reward must be 'sparse' or 'shaped', not {reward!r}")
        if render_mode not in (None, "rgb_array"):
            raise KintsugiError(f"render_mode must be None or 'rgb_array', not {render_mode!r}")
        self.images, self.reward_kind, self.shaped_scale = images, reward, shaped_scale
        self._shaped = reward == "shaped"
        self.score_every_s, self.period_s, self.render_mode = score_every_s, period_s, render_mode
        if perceived and self.task.system != "tabletop":
            raise KintsugiError(f"perceived=True adds the tabletop robot's perceived object features; {task} is "
                                f"a {self.task.system} task (its observation already has what its robot senses)")
        self.perceived = perceived
        self.max_seconds = max_seconds if max_seconds is not None else _default_seconds(self.cfg)
        self.episode: Any = None
        self.driver: Driver | None = None
        self._open(0)
        d = self.driver
        self.observation_space = spaces.Dict({k: _space(f) for k, f in d.features(images).items()})
        self.action_space = spaces.Box(d.action_low.astype(np.float32), d.action_high.astype(np.float32),
                                       dtype=np.float32)
        self.action_names = d.action_names
        self.score_every = max(1, round(score_every_s * d.control_hz))

    def _open(self, seed: int) -> None:
        if self.episode is not None:
            self.episode.close()
        self.episode = self.task.episode(self.cfg, self.variant, self.condition, seed)
        opts = {"period_s": self.period_s, "perceived": self.perceived} if self.task.system == "tabletop" else {}
        self.driver = driver_for(self.episode.robot, **opts)
        self.seed_used = seed
        self._ids = {"task": self.task_name, "variant": self.variant, "condition": self.condition, "seed": seed,
                     "success": False, "sim_time": 0.0, "physics_steps": 0, "steps": 0}
        """The info's fields, the trial's fixed ones filled: a step copies it (one table copy) and sets its own."""
        self._t_end = self.max_seconds - 1e-9
        self._succeeded = False
        self._last_action: np.ndarray | None = None
        self._world = self.driver.world
        self._data = self._world.data
        """The driven world and its MjData, bound once: the step reads the clock and the step count from them."""

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):  # noqa: ANN201
        super().reset(seed=seed)
        trial_seed = seed if seed is not None else int(self.np_random.integers(SEED_SPACE))
        self._open(int(trial_seed))
        info = self._info() | {"params": self.episode.params}
        return self.driver.observe(self.images), info

    def step(self, action: Any):  # noqa: ANN201
        d = self.driver
        obs, error = d.advance(action, self.images)
        if error is not None:
            return self._failed(action, error)
        t = self._data.time
        truncated = t >= self._t_end
        reward = 0.0
        if not self._succeeded and (truncated or d.steps % self.score_every == 0) and self.episode.score()[0]:
            self._succeeded = True
            reward = 1.0
        if self._shaped:
            reward -= self._change(d.clip(action))
        success = self._succeeded
        info = self._ids.copy()
        info["success"] = success
        info["sim_time"] = t
        info["physics_steps"] = self._world.steps
        info["steps"] = d.steps
        return obs, reward, success, truncated and not success, info

    def _change(self, a: np.ndarray) -> float:
        """The shaped term: `shaped_scale` x the mean normalised change of the action since the last step."""
        last, self._last_action = self._last_action, a
        if last is None:
            return 0.0
        span = np.maximum(self.driver.action_high - self.driver.action_low, 1e-9)
        return self.shaped_scale * float(np.abs((a - last) / span).mean())

    def _zeros(self) -> dict[str, np.ndarray]:
        return {k: np.zeros(s.shape, dtype=s.dtype) for k, s in self.observation_space.spaces.items()}

    def _info(self) -> dict[str, Any]:
        d = self.driver
        return self._ids | {"success": self._succeeded, "sim_time": d.sim_time, "physics_steps": d.physics_steps,
                            "steps": d.steps}

    def render(self) -> np.ndarray | None:
        return self.driver.render() if self.render_mode == "rgb_array" else None

    def close(self) -> None:
        if self.episode is not None:
            self.episode.close()
            self.episode = None


def _default_seconds(cfg: Any) -> float:
    """The task's own episode length where it states one (contact `control.episode_s`), else 60 s."""
    control = getattr(cfg, "control", None)
    return float(getattr(control, "episode_s", 60.0) or 60.0)
