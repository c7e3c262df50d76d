"""A CoRAL trial that recalls a remembered episode runs to its record like one that formulates."""

from __future__ import annotations

import pytest

from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.methods.coral.method import CoralFigures


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
