"""The drivers' observations are the worlds' own sensor readers, value for value: the step-level API reads them
with index arrays resolved once (its hot path), and these tests hold it to `world.base_pose`, `joint_positions`,
`tcp_pose`, `gripper_opening`, `pad_contacts` and `robot.observe()` at every step of a stretch with contacts."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.methods.policy.drivers import DriverError, driver_for
from kintsugi.worlds.tabletop.config import ARMS


def _episode(task: str, condition: str, seed: int):  # noqa: ANN202
    load_builtins()
    t = TASKS.get(task).factory()
    return t.episode(t.config({}), t.default_variants[0], condition, seed)


def _same_rotation(a: np.ndarray, b: np.ndarray) -> None:
    assert np.array_equal(a, b) or np.array_equal(a, -b)


def test_peg_observation_is_the_worlds_reading() -> None:
    ep = _episode("peg-insertion", "pose", 4)
    try:
        d = driver_for(ep.robot)
        target = d.command() + np.array([0.01, -0.2, 0.3])  # down into contact, rate-limited, rolling
        for _ in range(200):
            d.apply(target)
            d.tick()
            obs = d.observe(images=False)
            assert np.array_equal(obs["base_pose"], ep.world.base_pose())
            assert obs["wrist_force"].tolist() == [ep.robot.wrist_force_z()]
        assert obs["wrist_force"][0] != 0.0
    finally:
        ep.close()


def test_tabletop_observation_is_the_worlds_reading_pads_included() -> None:
    ep = _episode("pour-single", "none", 2)
    try:
        d = driver_for(ep.robot)
        w = ep.world
        squeeze = d.command()
        squeeze[6] = squeeze[13] = 1.0  # close both grippers: the pads press on each other
        forces = []
        for step in range(120):
            d.apply(squeeze if step >= 20 else d.command())
            d.tick()
            obs = d.observe(images=False)
            for arm in ARMS:
                pos, rot = w.tcp_pose(arm)
                wxyz = np.empty(4)
                mujoco.mju_mat2Quat(wxyz, rot.reshape(-1))
                assert np.array_equal(obs[f"{arm}_joint_pos"], w.joint_positions(arm))
                assert np.array_equal(obs[f"{arm}_eef_pos"], pos)
                _same_rotation(obs[f"{arm}_eef_quat"], wxyz[[1, 2, 3, 0]])
                assert obs[f"{arm}_gripper_opening"].tolist() == [w.gripper_opening(arm)]
                assert obs[f"{arm}_pad_force"].tolist() == [w.pad_contacts(arm)[1]]
                forces.append(obs[f"{arm}_pad_force"][0])
            assert np.array_equal(d.command()[[6, 13]], [1.0, 1.0] if step >= 20 else d.command()[[6, 13]])
        assert max(forces) > 0.0  # the comparison saw pad contacts, not only zeros
    finally:
        ep.close()


def test_contact_observation_is_the_robots_own() -> None:
    ep = _episode("push-force", "all", 1)
    try:
        d = driver_for(ep.robot)
        box = d.observe(images=False)["box_pos"]
        push = np.array([box[0] + 0.2, box[1], 0.01, 0.0, 0.0])  # through the box toward the wall: they meet
        for _ in range(250):
            d.apply(push)
            d.tick()
            obs = d.observe(images=False)
            o = ep.robot.observe()
            for key in ("ee", "ee_vel", "fingers", "finger_vel", "force", "torque", "touch"):
                assert np.array_equal(obs[key], getattr(o, key)), key
            for name, tr in o.objects.items():
                assert np.array_equal(obs[f"{name}_pos"], tr.pos)
                _same_rotation(obs[f"{name}_quat"], tr.quat)
                assert np.array_equal(obs[f"{name}_lin_vel"], tr.lin_vel)
                assert np.array_equal(obs[f"{name}_ang_vel"], tr.ang_vel)
        assert np.abs(obs["force"]).max() > 0.1  # a push with a real contact force
    finally:
        ep.close()


@pytest.mark.parametrize("bad", [[0.0, "x", 0.0], np.array(["a", "b", "c"]), [0.0, float("nan"), 0.0],
                                 np.array([0.0, np.inf, 0.0]), [0.0, 0.0], 3.0, np.array([1j, 0, 0])])
def test_a_bad_action_is_a_clear_error(bad: object) -> None:
    ep = _episode("peg-insertion", "pose", 0)
    try:
        with pytest.raises(DriverError, match="peg action"):
            driver_for(ep.robot).apply(bad)
    finally:
        ep.close()


def test_actions_are_clipped_to_the_bounds_as_floats() -> None:
    ep = _episode("push-force", "all", 0)
    try:
        d = driver_for(ep.robot)
        got = d.clip_values(np.array([9, -9, 0, 0, 0], dtype=np.int64))
        assert got[:2] == [d.action_high[0], d.action_low[1]] and all(type(v) is float for v in got)
    finally:
        ep.close()


@pytest.mark.parametrize("task", ["peg-insertion", "pour-single", "push-force"])
def test_every_driver_takes_any_shape_of_its_values_and_refuses_a_wrong_count_or_a_non_finite_value(task: str) -> None:
    ep = _episode(task, TASKS.get(task).factory().default_conditions[0], 0)
    try:
        d = driver_for(ep.robot)
        a = d.command()
        for shaped in (a.reshape(-1, 1), a.reshape(1, -1), a.astype(np.float32), list(a)):
            assert d.clip_values(shaped) == d.clip_values(np.asarray(shaped, dtype=np.float64).ravel())
        for bad in (np.append(a, 0.0), a[:-1], np.where(np.arange(a.size) == 1, np.nan, a),
                    np.where(np.arange(a.size) == 0, -np.inf, a)):
            with pytest.raises(DriverError, match=f"{d.family} action"):
                d.apply(bad)
    finally:
        ep.close()


@pytest.mark.parametrize("task", ["peg-insertion", "pour-single", "push-force"])
def test_the_fast_clip_is_the_checked_one(task: str) -> None:
    ep = _episode(task, TASKS.get(task).factory().default_conditions[0], 0)
    try:
        d = driver_for(ep.robot)
        lo, hi = d.action_low, d.action_high
        rng = np.random.default_rng(0)
        for _ in range(50):
            a = rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo))
            assert d.clip_values(a) == np.clip(a, lo, hi).tolist() == d.clip_values(a.tolist())
    finally:
        ep.close()


@pytest.mark.parametrize("task", ["peg-insertion", "pour-single", "push-force"])
def test_advance_is_apply_tick_observe(task: str) -> None:
    """A driver's fused step (what the environment calls) gives the observation `observe()` reads after the same
    command, and the arrays it returned are never written again."""
    eps = [_episode(task, TASKS.get(task).factory().default_conditions[0], 3) for _ in range(2)]
    try:
        a, b = (driver_for(ep.robot) for ep in eps)
        target = a.command() + 0.05 * (a.action_high - a.action_low)  # rate-limited (peg), a move (others)
        kept = []
        for _ in range(60):
            obs, error = a.advance(target, images=False)
            b.apply(target)
            b.tick()
            ref = b.observe(images=False)
            assert error is None and list(obs) == list(ref)
            assert all(np.array_equal(obs[k], ref[k]) for k in obs)
            kept.append((obs, {k: v.copy() for k, v in obs.items()}))
        assert all(np.array_equal(o[k], c[k]) for o, c in kept for k in o)
    finally:
        for ep in eps:
            ep.close()
