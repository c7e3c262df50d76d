"""System B's methods and reasoners never read a trial's truth.

The tabletop world's only truth accessor is `TabletopWorld.ground_truth()`. The scorer and the
disturbances (the environment) call it from inside the method's call stack, every control
tick, so an import check or a plain "who is on the stack" check proves nothing. This test
poisons the accessor by its *caller*: the nearest frame outside the world module must belong
to the environment (the task files, scorers, disturbances, conditions), never to the method
layer (methods, reasoning, task graph) or to the robot and perception a method drives. A
poisoned call raises; the records must equal the unpoisoned ones, recoveries included.
"""

from __future__ import annotations

import sys

import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import TrialSpec
from kintsugi.core.registry import TASKS
from kintsugi.core.runner import run_trial
from kintsugi.worlds.tabletop.world import TabletopWorld

load_builtins()

METHOD_SIDE = ("kintsugi.methods", "kintsugi.reasoning", "kintsugi.taskgraph", "kintsugi.worlds.tabletop.robot",
               "kintsugi.worlds.tabletop.perceive", "kintsugi.worlds.tabletop.motion",
               "kintsugi.worlds.tabletop.actions", "kintsugi.worlds.tabletop.planning", "kintsugi.perception")
WORLD = "kintsugi.worlds.tabletop.world"


class TruthAccessed(AssertionError):
    pass


def _caller_module() -> str:
    frame = sys._getframe(2)  # skip the guard and ground_truth's wrapper
    while frame is not None and frame.f_globals.get("__name__") == WORLD:
        frame = frame.f_back
    return frame.f_globals.get("__name__", "?") if frame is not None else "?"


def _guarded(real):  # noqa: ANN001, ANN202
    def ground_truth(self):  # noqa: ANN001, ANN202
        caller = _caller_module()
        if caller.startswith(METHOD_SIDE):
            raise TruthAccessed(f"{caller} read the world's ground truth")
        return real(self)

    return ground_truth


def _record(method: str, seed: int) -> dict:
    spec = TrialSpec(task="pour-single", method=method, variant="default", condition="drop", seed=seed,
                     overrides={"disturbance.drop_p": 0.1})
    return run_trial(spec).without_timings()


def test_the_guard_catches_a_method_side_read(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(TabletopWorld, "ground_truth", _guarded(TabletopWorld.ground_truth))
    fake = type(sys)("kintsugi.methods.agentchord.fake_reader")
    exec("def read(world):\n    return world.ground_truth()\n", fake.__dict__)  # noqa: S102 - test double
    task = TASKS.get("pour-single").factory()
    world, *_ = task.build(task.config({}), "none", 0)
    with pytest.raises(TruthAccessed, match="fake_reader"):
        fake.read(world)
    assert world.ground_truth() is not None  # the test module itself is environment-side


@pytest.mark.slow
@pytest.mark.parametrize("method", ["agentchord", "inner-monologue"])
def test_records_are_identical_with_the_truth_poisoned_for_the_method_side(
        method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    seed = 3  # pour-single, drop p = 0.1: the bottle is dropped mid-lift and recovered
    plain = _record(method, seed)
    monkeypatch.setattr(TabletopWorld, "ground_truth", _guarded(TabletopWorld.ground_truth))
    poisoned = _record(method, seed)
    assert "TruthAccessed" not in str(poisoned.get("error")), poisoned.get("error")
    assert poisoned == plain
    if method == "agentchord":
        assert plain["success"] and plain["error"] is None
