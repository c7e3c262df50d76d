"""One contract over every registered task and its default variants (dm_control suite_test style).

Built-in tasks and the toy plugins (tests/plugins) go through the same Task API and the one runner,
with nothing written per world: a new task passes this file or it is not done. Its attributes are
coherent (its reference and default methods exist and drive its robot, its default conditions and
variants are its own); its reference method's trial, on the task's short `contract_overrides`
budget, runs with no error; the physics stepped, with no MuJoCo warning and no NaN; the same seed
gives the same record; different seeds under condition "all" draw different hidden parameters, and
under "none" the same ones. Broken inputs (unknown method, variant, condition, override) become a
recorded error, never an exception.
"""

from __future__ import annotations

import math
from typing import Any

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import mujoco
import numpy as np
import pytest

from kintsugi.campaign.plan import build_config
from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_plugins
from kintsugi.core.record import TrialRecord, TrialSpec
from kintsugi.core.registry import METHODS, TASKS
from kintsugi.core.runner import run_trial

TOY_PLUGINS = ("tests.plugins.toy_tabletop", "tests.plugins.toy_contact", "tests.plugins.toy_method")
load_plugins(TOY_PLUGINS)
TASK_NAMES = [e.name for e in TASKS if "test" not in e.tags]
"""Every registered task: the built-ins, installed plugins and the toy plugins. Entries tagged `test`
(tests.fake_tasks' coin flips, registered when another test imports them) have no world to check."""
CASES = [(name, v) for name in TASK_NAMES for v in TASKS.get(name).factory().default_variants]
STATE = ("qpos", "qvel", "qacc", "act", "sensordata")


def _spec(task: str, variant: str, seed: int = 0, condition: str = "all", **kw: Any) -> TrialSpec:
    made = TASKS.get(task).factory()
    kw.setdefault("overrides", dict(made.contract_overrides))  # the task's short contract budget
    return TrialSpec(task=task, method=made.reference_method, variant=variant, condition=condition, seed=seed, **kw)


def _untimed(record: TrialRecord) -> dict[str, Any]:
    """The record minus wall-clock measurements (its timings and figures such as `*_ms_per_step`)."""
    return record.without_timings()


def _floats(value: Any) -> list[float]:
    if isinstance(value, float):
        return [value]
    if isinstance(value, dict):
        return [f for v in value.values() for f in _floats(v)]
    if isinstance(value, (list, tuple)):
        return [f for v in value for f in _floats(v)]
    return []


def _sampled(record: TrialRecord) -> dict[str, Any]:
    """The hidden parameters drawn for the trial (not outcomes such as the final tip depth)."""
    return {k: v for k, v in record.params.items() if not k.startswith("tip_")}


@pytest.fixture
def stepped(monkeypatch: pytest.MonkeyPatch) -> dict[int, mujoco.MjData]:
    """Every MjData that `mujoco.mj_step` advances during the test, whatever world or task owns it.

    Worlds step through `mujoco.mj_step`; watching it reads the warning counters and state of any
    task's simulation with nothing written per world. (MPPI's planning rollouts run in
    `mujoco.rollout` on the method's beliefs, not in the world.)
    """
    seen: dict[int, mujoco.MjData] = {}
    step = mujoco.mj_step

    def spy(model: mujoco.MjModel, data: mujoco.MjData, *args: Any, **kwargs: Any) -> None:
        seen.setdefault(id(data), data)
        step(model, data, *args, **kwargs)

    monkeypatch.setattr(mujoco, "mj_step", spy)
    return seen


def _check_physics(task: str, stepped: dict[int, mujoco.MjData]) -> None:
    """Every simulation stepped so far: no MuJoCo warning of any kind, a finite state."""
    assert stepped, f"{task} stepped no simulation through mujoco.mj_step"
    for data in stepped.values():
        warnings = {mujoco.mjtWarning(i).name: data.warning[i].number
                    for i in range(mujoco.mjtWarning.mjNWARNING) if data.warning[i].number}
        assert not warnings, warnings
        for name in STATE:
            assert np.all(np.isfinite(getattr(data, name))), name
        assert data.time > 0


def test_every_task_is_covered() -> None:
    assert {"peg-insertion", "pour-single", "pick-box", "toy-lift-block", "toy-raise-cube"} <= set(TASK_NAMES)


@pytest.mark.parametrize("task", TASK_NAMES)
def test_task_attributes_are_coherent(task: str) -> None:
    made = TASKS.get(task).factory()
    assert made.name == task and made.system and made.description
    for role, name in (("reference", made.reference_method), ("default", made.default_method or made.reference_method)):
        entry = METHODS.get(name)  # raises, naming the registered methods, for a method that does not exist
        assert made.method_tag in entry.tags, f"{task}'s {role} method {name!r} does not drive its robot"
    assert "none" in made.conditions and "all" in made.conditions
    assert made.default_conditions and set(made.default_conditions) <= set(made.conditions), made.default_conditions
    assert made.default_variants
    methods = sorted({made.reference_method, made.default_method or made.reference_method})
    # What a campaign checks before its first trial: methods, contract overrides, variants, conditions.
    build_config(task=task, methods=methods, variants=list(made.default_variants),
                 conditions=list(made.default_conditions), overrides=dict(made.contract_overrides), trials=1)
    with pytest.raises(ConfigError):
        made.check_variant("no-such-variant", made.config({}))


@pytest.mark.slow
@pytest.mark.parametrize(("task", "variant"), CASES)
def test_task_contract(task: str, variant: str, stepped: dict[int, mujoco.MjData]) -> None:
    # The reference method's trial: no error, physics stepped, no NaN anywhere in the record.
    first = run_trial(_spec(task, variant, seed=0))
    assert first.error is None, first.error
    assert first.physics_steps > 0 and first.sim_time > 0
    assert all(math.isfinite(f) for f in _floats(first.model_dump(mode="python"))), first
    # Same seed -> identical record apart from wall-clock timings.
    again = run_trial(_spec(task, variant, seed=0))
    assert _untimed(again) == _untimed(first)
    # Different seeds under "all" -> different hidden parameters.
    other = run_trial(_spec(task, variant, seed=1))
    assert other.error is None, other.error
    a, b = _sampled(first), _sampled(other)
    assert a.keys() == b.keys()
    assert {k for k in a if a[k] != b[k]}, f"seeds 0 and 1 sampled the same parameters: {a}"
    _check_physics(task, stepped)  # every simulation the three trials stepped


@pytest.mark.slow
@pytest.mark.parametrize("task", TASK_NAMES)
def test_condition_none_is_the_nominal_world(task: str) -> None:
    """Seeds differ only where the condition randomizes: under "none" the hidden truth is fixed."""
    variant = TASKS.get(task).factory().default_variants[0]
    a = run_trial(_spec(task, variant, seed=0, condition="none"))
    b = run_trial(_spec(task, variant, seed=7, condition="none"))
    assert a.error is None and b.error is None, a.error or b.error
    assert _sampled(a) == _sampled(b)


@pytest.mark.parametrize(("field", "value", "needles"), [
    ("method", "no-such-method", ["unknown method 'no-such-method'", "baseline"]),
    ("variant", "hexagon", ["unknown peg shape 'hexagon'", "round"]),
    ("variant", "polygon2", ["unknown peg shape 'polygon2'", "polygonN"]),
    ("condition", "storm", ["unknown condition 'storm'", "friction", "pose", "all"]),
    ("task", "no-such-task", ["unknown task 'no-such-task'", "peg-insertion"]),
])
def test_bad_names_become_a_recorded_error(field: str, value: str, needles: list[str]) -> None:
    fields = {"task": "peg-insertion", "method": "baseline", "variant": "round", "condition": "all", "seed": 0}
    fields[field] = value
    record = run_trial(TrialSpec(**fields))  # must not raise
    assert record.error, record
    for needle in needles:
        assert needle in record.error, record.error
    assert not record.success and not record.framework_success
    assert record.key == TrialSpec(**fields).key


def test_bad_override_becomes_a_recorded_error() -> None:
    record = run_trial(_spec("peg-insertion", "round", overrides={"hole.no_such_key": 1}))
    assert record.error and "ConfigError" in record.error and "hole.no_such_key" in record.error
    record = run_trial(_spec("peg-insertion", "round", overrides={"peg.clearance_mm": -1}))
    assert record.error and "peg.clearance_mm" in record.error


def test_the_physics_check_sees_a_stepped_simulations_warnings(stepped: dict[int, mujoco.MjData]) -> None:
    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body>"
                                           "</worldbody></mujoco>")
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data)
    _check_physics("a ball", stepped)
    data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number = 1
    with pytest.raises(AssertionError, match="mjWARN_BADQACC"):
        _check_physics("a ball", stepped)
    data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number = 0
    data.qvel[0] = np.nan
    with pytest.raises(AssertionError, match="qvel"):
        _check_physics("a ball", stepped)
