"""The recovery method and its reasoner never read a trial's truth.

Run the same trials twice: normally, and with every truth container of the
world (the trial parameters, the hole, the peg) replaced, for everyone but the
scorer, by an object that raises on any use. The records must be identical:
nothing the method decided can have come from the truth. The trial seed is not
poisoned because the method is never given it (PegContext has no seed).
"""

from __future__ import annotations

import dataclasses

import pytest

import kintsugi.worlds.peg.task as task_module
from kintsugi.core.plugins import load_builtins
from kintsugi.worlds.peg.context import PegContext
from kintsugi.worlds.peg.suites import suite_overrides
from kintsugi.worlds.peg.world import PegWorld
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial

load_builtins()

TRUTH = ("params", "hole", "peg")
"""PegWorld attributes that hold what a trial randomized or what only the simulator knows."""


class TruthAccessed(AssertionError):
    pass


class Poison:
    """Stands in for a truth object: any attribute, call, comparison, conversion or iteration raises."""

    __slots__ = ("_name",)

    def __init__(self, name: str) -> None:
        object.__setattr__(self, "_name", name)

    def _fail(self, *args: object, **kwargs: object) -> None:
        raise TruthAccessed(f"the method path touched the world's truth: {object.__getattribute__(self, '_name')}")

    def __getattribute__(self, attr: str) -> object:
        object.__getattribute__(self, "_fail")()

    __setattr__ = __call__ = __eq__ = __ne__ = __lt__ = __gt__ = __hash__ = __bool__ = _fail
    __iter__ = __len__ = __getitem__ = __contains__ = __int__ = __float__ = __index__ = _fail
    __str__ = __repr__ = __format__ = __reduce__ = __reduce_ex__ = __copy__ = __deepcopy__ = _fail


class PoisonedWorld(PegWorld):
    """A PegWorld whose truth raises for everyone except `ground_truth()` (the scorer)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)
        self._real_truth = {name: getattr(self, name) for name in TRUTH}
        self._poison()

    def _poison(self) -> None:
        for name in TRUTH:
            setattr(self, name, Poison(f"PegWorld.{name}"))

    def ground_truth(self):  # noqa: ANN201 - scoring reads the real truth
        for name, value in self._real_truth.items():
            setattr(self, name, value)
        try:
            return super().ground_truth()
        finally:
            self._poison()


def _records(shape: str, seeds: range, overrides: dict | None = None) -> list[dict]:
    return [run_trial(TrialSpec(task="peg-insertion", method="recovery", variant=shape, condition="all", seed=s,
                                overrides=overrides or {})).without_timings() for s in seeds]


def test_poison_raises_on_any_use() -> None:
    p = Poison("x")
    for use in (lambda: p.hole_y_mm, lambda: p == 1, lambda: str(p), lambda: float(p), lambda: bool(p),
                lambda: list(p), lambda: f"{p}", lambda: p.model_dump()):
        with pytest.raises(TruthAccessed):
            use()


def test_context_carries_no_seed_or_trial_parameters() -> None:
    names = {f.name for f in dataclasses.fields(PegContext)}
    assert names == {"cfg", "shape", "reasoner", "goals"}


@pytest.mark.slow
@pytest.mark.parametrize("shape", ["round", "square"])
def test_recovery_records_are_identical_with_the_truth_poisoned(shape: str, monkeypatch: pytest.MonkeyPatch) -> None:
    seeds = range(3)
    normal = _records(shape, seeds)
    monkeypatch.setattr(task_module, "PegWorld", PoisonedWorld)
    poisoned = _records(shape, seeds)
    assert [r["error"] for r in poisoned] == [None] * len(seeds)
    assert poisoned == normal
    # The trials exercised the whole loop, recoveries included, and were scored from the real truth.
    assert sum(sum(r["method_figures"]["extra_executions"].values()) for r in normal) > 0
    assert {c["role"] for r in normal for c in r["transcript"]} == {"judge", "analyze", "plan"}
    assert all(r["params"]["shape"] == shape and "tip_depth_mm" in r["params"] for r in poisoned)


@pytest.mark.slow
def test_stretch_options_never_read_the_truth(monkeypatch: pytest.MonkeyPatch) -> None:
    """Re-approach (which re-locates the hole from the approach image) and the side camera, in the stretch
    world: identical records with the truth poisoned, and the re-approach path was exercised."""
    overrides, seeds = suite_overrides("stretch"), range(4)
    normal = _records("round", seeds, overrides)
    monkeypatch.setattr(task_module, "PegWorld", PoisonedWorld)
    poisoned = _records("round", seeds, overrides)
    assert [r["error"] for r in poisoned] == [None] * len(seeds)
    assert poisoned == normal
    assert any("approach" in str(r["transitions"]) for r in normal), [r["transitions"] for r in normal]
