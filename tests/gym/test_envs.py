"""Every registered task as a Gymnasium environment: `check_env` passes (spaces, seeding, determinism, step API);
one task per system also with camera images and `render_mode="rgb_array"`; a reset draws the campaign's trial."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import kintsugi.gym  # noqa: E402 - registers the environments
from gymnasium.utils.env_checker import check_env  # noqa: E402

from kintsugi.core.errors import KintsugiError  # noqa: E402
from kintsugi.core.registry import TASKS  # noqa: E402

IMAGED = ("kintsugi/PegInsertion-v0", "kintsugi/PourSingle-v0", "kintsugi/PickBox-v0")


def _check(env) -> None:  # noqa: ANN001
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # unbounded force/velocity boxes, unnormalised actions
        check_env(env, skip_render_check=env.render_mode is None)


@pytest.mark.parametrize("env_id", kintsugi.gym.ENV_IDS)
def test_check_env_passes_without_images(env_id: str) -> None:
    env = gym.make(env_id, images=False).unwrapped
    try:
        _check(env)
        assert not any(s.dtype == np.uint8 for s in env.observation_space.spaces.values())
    finally:
        env.close()


@pytest.mark.parametrize("env_id", IMAGED)
def test_check_env_passes_with_images_and_rendering(env_id: str) -> None:
    env = gym.make(env_id, render_mode="rgb_array").unwrapped
    try:
        _check(env)
        obs, _ = env.reset(seed=3)
        imgs = [k for k, s in env.observation_space.spaces.items() if s.dtype == np.uint8]
        assert imgs and all(obs[k].dtype == np.uint8 and obs[k].std() > 1.0 for k in imgs)  # a real render
        assert env.render().ndim == 3
    finally:
        env.close()


def test_every_task_has_an_environment() -> None:
    assert len(kintsugi.gym.ENV_IDS) == len(TASKS.names())
    assert "kintsugi/PourSingle-v0" in gym.registry and "kintsugi/PegInsertion-v0" in gym.registry


def test_reset_draws_the_campaign_trial_of_that_seed() -> None:
    env = gym.make("kintsugi/PourSingle-v0", condition="pose", images=False).unwrapped
    try:
        _, info = env.reset(seed=7)
        task = TASKS.get("pour-single").factory()
        ep = task.episode(task.config({}), "default", "pose", 7)
        assert info["params"] == ep.params and info["seed"] == 7
        ep.close()
        _, other = env.reset(seed=8)
        assert other["params"] != info["params"]
    finally:
        env.close()


def test_forces_and_continuous_quaternions_are_in_the_observation() -> None:
    env = gym.make("kintsugi/PourSingle-v0", images=False).unwrapped
    try:
        obs, _ = env.reset(seed=1)
        assert "right_pad_force" in obs and obs["right_eef_quat"].shape == (4,)
        prev = obs["left_eef_quat"]
        for _ in range(30):
            obs, *_ = env.step(env.driver.command())  # hold the command in force
            assert obs["left_eef_quat"] @ prev > 0  # never jumps to the other hemisphere
            prev = obs["left_eef_quat"]
    finally:
        env.close()


def test_time_limit_truncates_and_bad_options_are_one_line_errors() -> None:
    env = gym.make("kintsugi/PegInsertion-v0", images=False, max_seconds=0.02).unwrapped
    try:
        env.reset(seed=0)
        results = [env.step(env.driver.command()) for _ in range(5)]
        assert results[-1][3] is True and results[-1][2] is False
    finally:
        env.close()
    with pytest.raises(KintsugiError, match="unknown condition"):
        gym.make("kintsugi/PourSingle-v0", condition="earthquake")
    with pytest.raises(KintsugiError, match="reward must be"):
        gym.make("kintsugi/PegInsertion-v0", reward="dense")


def test_perceived_features_are_an_option_of_the_tabletop_environment() -> None:
    env = gym.make("kintsugi/PourSingle-v0", images=False, perceived=True).unwrapped
    try:
        _check(env)
        obs, _ = env.reset(seed=2)
        assert obs["bottle_visible"][0] == 1.0 and 0.0 < obs["bottle_centroid"][2] < 0.5
        assert abs(np.linalg.norm(obs["bottle_axis"]) - 1.0) < 1e-6
    finally:
        env.close()
    with pytest.raises(KintsugiError, match="perceived=True"):
        gym.make("kintsugi/PegInsertion-v0", perceived=True)
