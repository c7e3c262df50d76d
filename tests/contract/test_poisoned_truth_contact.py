"""System C's methods never read a trial's truth.

The contact world's truth is reachable three ways, and each is poisoned for the method side:

- the evaluation world's accessors (`physics_of`, `pusher_force`, `pinched`, `touching_pads`,
  `object_pose`, `object_velocity`) raise unless the nearest caller outside the world module is the
  environment (task files, scorers) or, for poses and velocities only, the robot's pose tracker;
- the robot's handle on its evaluation world (`ContactRobot._world`) raises for any module but the
  robot's own (a method holding the robot cannot reach the model's masses through it);
- a non-oracle method's context is built from a setup whose truth, catalogue midpoints and drawn
  parameters, and from a trial seed, that raise on any use.

The records of every C method, poisoned and not, must be identical. Oracle methods (`expert`,
`expert-fsm`) are given the true physics and the seed by design; they are run too, so that the
world accessors and the robot's handle are proven unread by them as well.
"""

from __future__ import annotations

import dataclasses
import sys

import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import ReasonerSettings, TrialSpec
from kintsugi.core.registry import TASKS
from kintsugi.core.runner import run_trial
from kintsugi.worlds.contact.context import ORACLE_TAG
from kintsugi.worlds.contact.robot import ContactRobot
from kintsugi.worlds.contact.task import ContactEpisode
from kintsugi.worlds.contact.world import EvaluationWorld

load_builtins()

WORLD = "kintsugi.worlds.contact.world"
ROBOT = "kintsugi.worlds.contact.robot"
METHOD_SIDE = ("kintsugi.methods", "kintsugi.reasoning", "kintsugi.control", "kintsugi.sandbox",
               "kintsugi.perception", "kintsugi.taskgraph", ROBOT)
TRACKER = ("object_pose", "object_velocity")
"""What the robot's pose tracker reads (where objects are, never what they weigh)."""
TRUTH = ("physics_of", "pusher_force", "pinched", "touching_pads", *TRACKER)
METHODS = ("coral", "l2r", "coral-no-memory", "coral-no-refinement", "coral-no-contact", "mppi-sysid",
           "expert", "expert-fsm")
SHORT = {"control.samples": 16, "control.episode_s": 1.2, "coral.max_attempts": 2, "sysid.max_attempts": 2}
"""Two short attempts: the first fails on its budget, so system identification and adaptation run too."""


class TruthAccessed(AssertionError):
    pass


class Poison:
    """Stands in for a truth value: any use raises."""

    __slots__ = ("_name",)

    def __init__(self, name: str) -> None:
        object.__setattr__(self, "_name", name)

    def _fail(self, *args: object, **kwargs: object) -> None:
        raise TruthAccessed(f"a method's context used the trial's {object.__getattribute__(self, '_name')}")

    def __getattribute__(self, attr: str) -> object:
        object.__getattribute__(self, "_fail")()

    __setattr__ = __call__ = __eq__ = __ne__ = __lt__ = __gt__ = __hash__ = __bool__ = _fail
    __iter__ = __len__ = __getitem__ = __contains__ = __int__ = __float__ = __index__ = __add__ = __radd__ = _fail
    __mul__ = __rmul__ = __str__ = __repr__ = __format__ = __reduce__ = __reduce_ex__ = __copy__ = _fail
    __deepcopy__ = _fail


def _caller(depth: int) -> str:
    frame = sys._getframe(depth)
    while frame is not None and frame.f_globals.get("__name__") == WORLD:
        frame = frame.f_back
    return frame.f_globals.get("__name__", "?") if frame is not None else "?"


def _guard_world(name: str, real):  # noqa: ANN001, ANN202
    def accessor(self, *args, **kwargs):  # noqa: ANN001, ANN202
        caller = _caller(2)
        allowed = name in TRACKER and caller == ROBOT
        if caller.startswith(METHOD_SIDE) and not allowed:
            raise TruthAccessed(f"{caller} called EvaluationWorld.{name}")
        return real(self, *args, **kwargs)

    return accessor


def _robot_world() -> property:
    def get(self):  # noqa: ANN001, ANN202
        caller = sys._getframe(1).f_globals.get("__name__", "?")
        if caller != ROBOT:
            raise TruthAccessed(f"{caller} reached the robot's evaluation world")
        return self.__dict__["_poisoned_world"]

    def put(self, world) -> None:  # noqa: ANN001
        self.__dict__["_poisoned_world"] = world

    return property(get, put)


def _poisoned_context(real):  # noqa: ANN001, ANN202
    def context(self, tags, reasoner, seed):  # noqa: ANN001, ANN202
        given = real(self, tags, reasoner, seed)  # the episode's own side runs as in a plain trial (the robot's camera)
        if ORACLE_TAG in tags:
            return given
        setup = dataclasses.replace(self.setup, truth=Poison("truth"), nominal=Poison("catalogue midpoints"),
                                    params=Poison("drawn parameters"))
        return self.task.context(self.cfg, setup, False, reasoner, Poison("seed"))

    return context


def _poison(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in TRUTH:
        monkeypatch.setattr(EvaluationWorld, name, _guard_world(name, getattr(EvaluationWorld, name)))
    monkeypatch.setattr(ContactRobot, "_world", _robot_world(), raising=False)
    monkeypatch.setattr(ContactEpisode, "context", _poisoned_context(ContactEpisode.context))


def _record(task: str, method: str, seed: int) -> dict:
    return run_trial(TrialSpec(task=task, method=method, variant="default", condition="all", seed=seed,
                               overrides=SHORT)).without_timings()


def test_the_guards_catch_a_method_side_read(monkeypatch: pytest.MonkeyPatch) -> None:
    _poison(monkeypatch)
    task = TASKS.get("push-force").factory()
    episode = task.episode(task.config({}), "default", "all", 0)
    fake = type(sys)("kintsugi.methods.coral.fake_reader")
    exec("def mass(world):\n    return world.physics_of('box')\n"  # noqa: S102 - test doubles
         "def pose(world):\n    return world.object_pose('box')\n"
         "def through(robot):\n    return robot._world\n", fake.__dict__)
    with pytest.raises(TruthAccessed, match="fake_reader"):
        fake.mass(episode.world)
    with pytest.raises(TruthAccessed, match="fake_reader"):
        fake.pose(episode.world)
    with pytest.raises(TruthAccessed, match="fake_reader"):
        fake.through(episode.robot)
    assert episode.robot.observe().objects["box"].pos.shape == (3,)  # the tracker itself still reads poses
    ctx = episode.context(frozenset({"system-c"}), ReasonerSettings(), 0)
    assert ctx.oracle_physics is None and ctx.seed is None
    assert ctx.cfg.box.mass_kg is None and ctx.cfg.box.size_m is None  # no range reaches the method
    assert ctx.cfg.force.target_n == 5.0  # the task's fixed facts do
    assert not hasattr(ctx.task, "build") and not hasattr(ctx.task, "scorer")
    oracle = episode.context(frozenset({"system-c", ORACLE_TAG}), ReasonerSettings(), 0)
    assert oracle.oracle_physics is not None and oracle.seed == 0


def test_the_method_side_never_names_the_evaluation_world() -> None:
    """No method-side module imports the evaluation world or reaches into a robot's private handle."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2] / "kintsugi"
    offenders = []
    for folder in ("methods/coral", "methods/mppi", "methods/expert", "control", "sandbox"):
        for path in (root / folder).rglob("*.py"):
            text = path.read_text()
            if "EvaluationWorld" in text or "._world" in text:
                offenders.append(str(path.relative_to(root)))
    assert not offenders, offenders


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_records_are_identical_with_the_truth_poisoned(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    task = "pick-clutter" if method == "mppi-sysid" else "pick-box"
    plain = _record(task, method, 7)
    _poison(monkeypatch)
    poisoned = _record(task, method, 7)
    assert "TruthAccessed" not in str(poisoned.get("error")), poisoned.get("error")
    assert plain["error"] is None, plain["error"]
    assert poisoned == plain
