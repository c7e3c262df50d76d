"""AgentChord waits for a dropped object to come to rest once per drop, as the baselines do.

A recovery that is itself disturbed (the re-grasped block dropped again as it rose) runs again after one
settle: it used to wait twice, three reads more (27 control steps) than the backtracking baseline on the same
seed. A recovery that merges straight into the goal is judged on the scene its settle already found at rest:
the goal check used to wait three reads more (24 steps) than a re-planner that found the goal already held."""

from __future__ import annotations

import pytest

from kintsugi.methods.agentchord.method import metrics_of
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

STEP_SLACK = 0.002
"""How far AgentChord may run past a baseline's recorded steps on the same seed, as a fraction of them. A
settle ends when a read finds the object at rest, so machine-dependent floating point (CPU, BLAS build) moves
a trial by a control step or so: on seed 64, where rekep's steps were recorded as 1662, both rekep and
AgentChord take 1663 on another machine. 0.2 % of ~1600 steps is ~3 steps, far below the 24-27 steps that a
second settle costs."""


def within(steps: int, baseline_steps: int) -> bool:
    """No more steps than the baseline's, up to the floating-point slack."""
    return steps <= baseline_steps * (1 + STEP_SLACK)


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "rekep_steps"), [(56, 1565), (64, 1662)])
def test_a_disturbed_recovery_settles_once(seed: int, rekep_steps: int) -> None:
    r = run_trial(TrialSpec(task="handover-block", method="agentchord", variant="default", condition="drop",
                            seed=seed, overrides={"disturbance.drop_p": 0.1}))
    assert r.error is None, r.error
    assert r.success and r.framework_success
    assert any(e.kind == "recovery disturbed" for e in r.events)
    settles = [s for s in r.skills if s.skill == "open_gripper" and s.recovery]
    assert len(settles) <= 9  # two settles of at most five reads each (seed 56 took 12 when it settled twice)
    m = metrics_of(r)
    assert m.recoveries == 2 and within(m.episode_steps, rekep_steps), m.episode_steps


@pytest.mark.slow
def test_a_recovery_into_the_goal_is_judged_without_waiting_again() -> None:
    """Pour-single seed 41: the bottle drops as the hand turns it back from pouring; the branch lets it come to
    rest and merges into the goal (it has poured, and the bottle is out of the hand). Code-as-monitor, which
    re-plans and finds the goal held, takes 885 steps."""
    r = run_trial(TrialSpec(task="pour-single", method="agentchord", variant="default", condition="drop", seed=41,
                            overrides={"disturbance.drop_p": 0.1}))
    assert r.error is None, r.error
    assert r.success and r.framework_success
    m = metrics_of(r)
    assert m.recoveries == 1 and within(m.episode_steps, 885), m.episode_steps
