"""The policy method replays a recorded trial's low-level commands through the step-level drivers and
reproduces it step for step (physics steps, scored success, the source's verdict): peg (recovery under
the paper's randomization), contact (a two-attempt pusher with a restart between), tabletop (a four-action lift
with a drop disturbance timed by the source's atomic actions; in the slow set, an AgentChord trial that recovers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import TrialSpec
from kintsugi.core.registry import METHODS
from kintsugi.core.runner import run_trial
from kintsugi.methods.policy.policies import load_policy
from kintsugi.methods.policy.trajectory import TickRecorder, Trajectory

load_builtins()


class _TwoPushes:
    """A contact 'method' for the test: two attempts of a fixed push with a restart between."""

    def __init__(self, ctx, settings) -> None:  # noqa: ANN001
        pass

    def run(self, robot, log) -> bool:  # noqa: ANN001
        home = robot.observe().ctrl.copy()
        for dx in (0.03, -0.02):
            robot.act(home + np.array([dx, 0.0, -0.01, 0.0, 0.0]), 0.4)
            if dx > 0:
                robot.restart()
        return False


if "test-two-pushes" not in METHODS:
    METHODS.register("test-two-pushes", "test only", tags=("system-c",))(_TwoPushes)


class _LiftBottle:
    """A tabletop 'method' for the test: grasp the bottle, lift it, set it down, let go (four atomic actions)."""

    def __init__(self, ctx, settings) -> None:  # noqa: ANN001
        pass

    def run(self, robot, log) -> bool:  # noqa: ANN001
        for action in ({"action": "grasp", "arm": "right", "obj": "bottle"},
                       {"action": "move_by_offset", "arm": "right", "dxyz": [0.0, 0.0, 0.08]},
                       {"action": "move_by_offset", "arm": "right", "dxyz": [0.0, 0.0, -0.07]},
                       {"action": "open_gripper", "arm": "right"}):
            robot.execute(action)
        return False


if "test-lift-bottle" not in METHODS:
    METHODS.register("test-lift-bottle", "test only", tags=("system-b",))(_LiftBottle)


def _record_and_replay(spec: TrialSpec, tmp_path: Path):  # noqa: ANN202
    rec = TickRecorder()
    source = run_trial(spec, attach=rec.attach)
    assert source.error is None, source.error
    path = rec.trajectory(source).save(tmp_path / "traj.npz")
    again = run_trial(spec.model_copy(update={"method": "policy",
                                              "overrides": {**spec.overrides, "method.path": str(path)}}))
    assert again.error is None, again.error
    return source, again, Trajectory.load(path)


def test_peg_recovery_trial_replays_step_for_step(tmp_path: Path) -> None:
    spec = TrialSpec(task="peg-insertion", method="recovery", variant="round", condition="all", seed=3)
    source, again, traj = _record_and_replay(spec, tmp_path)
    assert again.physics_steps == source.physics_steps and len(traj.actions) * 4 == source.physics_steps
    assert (again.success, again.framework_success) == (source.success, source.framework_success)
    assert again.params == source.params  # the same final tip depth and tilt, to the recorded digits


def test_contact_restarts_replay_step_for_step(tmp_path: Path) -> None:
    spec = TrialSpec(task="push-force", method="test-two-pushes", variant="default", condition="all", seed=1)
    source, again, traj = _record_and_replay(spec, tmp_path)
    assert traj.restarts == [40] and len(traj.actions) == 80
    assert again.physics_steps == source.physics_steps
    assert again.task_figures == source.task_figures


def test_tabletop_trial_with_a_drop_replays_with_its_action_starts(tmp_path: Path) -> None:
    spec = TrialSpec(task="pour-single", method="test-lift-bottle", variant="default", condition="drop", seed=0,
                     overrides={"disturbance.drop_p": 1.0})
    source, again, traj = _record_and_replay(spec, tmp_path)
    assert len(traj.marks) == 4  # the four atomic actions' starts, where the drop draws are made
    drops = [e.detail for e in source.events if e.kind == "disturbance"]
    assert drops and drops == [e.detail for e in again.events if e.kind == "disturbance"]
    assert again.physics_steps == source.physics_steps and again.success == source.success
    assert again.task_figures == source.task_figures and again.params == source.params


@pytest.mark.slow
def test_tabletop_drop_trial_replays_with_the_source_action_starts(tmp_path: Path) -> None:
    spec = TrialSpec(task="pour-single", method="agentchord", variant="default", condition="drop", seed=22,
                     overrides={"disturbance.drop_p": 0.1})
    source, again, traj = _record_and_replay(spec, tmp_path)
    assert source.transitions and traj.marks  # the source recovered from a drop
    drops = [e.detail for e in source.events if e.kind == "disturbance"]
    assert drops and drops == [e.detail for e in again.events if e.kind == "disturbance"]
    assert again.physics_steps == source.physics_steps and again.success == source.success
    assert again.task_figures == source.task_figures


def test_a_policy_that_claims_nothing_is_no_success_for_the_method() -> None:
    spec = TrialSpec(task="peg-insertion", method="policy", variant="round", condition="none", seed=0,
                     overrides={"method.path": "tests.methods.policy.test_replay:hold", "method.max_seconds": 0.2})
    r = run_trial(spec)
    assert r.error is None and r.framework_success is False and r.physics_steps == 200


def hold(obs: dict) -> np.ndarray:
    return obs["base_pose"]


def test_bad_policies_are_one_line_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="needs a policy"):
        load_policy("")
    with pytest.raises(ConfigError, match="not found"):
        load_policy("no_such_module_xyz:f")
    with pytest.raises(ConfigError, match="no attribute"):
        load_policy("numpy:no_such_policy")
    with pytest.raises(ConfigError, match="not found"):
        load_policy(str(tmp_path / "missing.npz"))
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ConfigError, match="no kintsugi policy"):
        load_policy(str(tmp_path / "other.npz"))


def test_a_wrong_sized_action_is_a_recorded_refusal() -> None:
    spec = TrialSpec(task="peg-insertion", method="policy", variant="round", condition="none", seed=0,
                     overrides={"method.path": "tests.methods.policy.test_replay:too_long"})
    r = run_trial(spec)
    assert r.error is None and not r.framework_success
    assert any("refused action" in e.detail and "3 values" in e.detail for e in r.events)


def too_long(obs: dict) -> np.ndarray:
    return np.zeros(5)
