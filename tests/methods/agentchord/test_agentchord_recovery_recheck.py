"""After a recovery merges at the failed edge's target, the failed edge's drop checks are not read again with
no window: the recovery's own loss watch judged them with Eq. 12's window, as the nominal edge's watch does."""

from __future__ import annotations

import pytest

from kintsugi.methods.agentchord.method import metrics_of
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial


@pytest.mark.slow
def test_a_hand_that_lets_go_as_the_tray_lands_does_not_rerun_the_recovery() -> None:
    """Coffee-tray seed 13 at drop p 0.10: the tray falls from both hands during the carry; the branch takes it
    again and carries it on, and as it is set down the left pads slide off its rim in the last control steps.
    Read once more with no window, that fired the drop monitor and the same recovery ran four more times."""
    r = run_trial(TrialSpec(task="coffee-tray", method="agentchord", variant="default", condition="drop", seed=13,
                            overrides={"disturbance.drop_p": 0.1}))
    assert r.error is None, r.error
    m = metrics_of(r)
    assert [e.kind for e in r.events].count("monitor") == 1 and m.recoveries == 1
    assert r.success and r.framework_success and m.episode_steps < 1300
