"""A CoRAL trial's typed figures, from real trials: a recalled episode, an adapted attempt."""

from __future__ import annotations

import pytest

from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.methods.coral.figures import CoralFigures


@pytest.mark.slow
def test_a_second_trial_recalls_the_first_and_records_it(tmp_path) -> None:
    memory = {"coral.memory_path": str(tmp_path / "memory.sqlite")}
    first, second = (run_trial(TrialSpec(task="flip-box", method="coral", variant="default", condition="all",
                                         seed=seed, overrides=memory)) for seed in (0, 1))
    assert first.error is None and second.error is None, (first.error, second.error)
    a, b = CoralFigures.of(first), CoralFigures.of(second)
    assert a.plan_from == "formulation" and b.plan_from.startswith("memory episode")
    assert b.memory_beliefs and set(b.memory_beliefs) == set(b.priors)
    assert second.reasoning_calls == 1  # the priors; the recalled plan replaced the formulation call


def test_a_failed_attempt_records_its_adaptation_in_typed_figures() -> None:
    """One second of budget cannot tip the box from the start: the first attempt fails, sysid and the adaptation
    run (the second may or may not finish; its verdict is never looser than the scorer)."""
    r = run_trial(TrialSpec(task="flip-box", method="coral", variant="default", condition="all", seed=0,
                            overrides={"control.episode_s": 1.0, "coral.max_attempts": 2, "control.samples": 32}))
    assert r.error is None and (r.success or not r.framework_success)
    first, second = CoralFigures.of(r).attempts
    assert not first.reached and first.adaptation and first.sysid is not None and first.history is not None
    assert first.beliefs_after == second.beliefs_before
