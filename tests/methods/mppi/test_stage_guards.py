"""A stage machine's guards: path constraints checked on every observation, the inner rate's included."""

from __future__ import annotations

import numpy as np

from kintsugi.methods.mppi.fsm import Stage, StageMachine
from kintsugi.worlds.contact.robot import Observation


def _obs(t: float) -> Observation:
    z = np.zeros(3)
    return Observation(t=t, ee=np.zeros(4), ee_vel=np.zeros(4), fingers=np.zeros(2), finger_vel=np.zeros(2), force=z,
                       torque=z, touch=np.zeros(2), objects={}, ctrl=np.zeros(5))


def _stage(name: str, done_at: float):  # noqa: ANN202
    return lambda obs: Stage(name=name, cost=lambda view: np.zeros(1), done=lambda o: o.t >= done_at)


def test_a_guard_that_breaks_between_two_updates_fails_the_stage_and_the_attempt() -> None:
    machine = StageMachine([_stage("a", 0.2), _stage("b", 0.5)],
                           guards=(lambda o: "too close" if 0.33 <= o.t < 0.34 else None,))
    for i in range(60):
        obs = _obs(i * 0.01)
        if i % 10 == 0:  # the planner's replans; the ticks between are the inner rate's
            machine.update(obs)
        else:
            machine.watch(obs)
    assert machine.finished and not machine.succeeded and machine.broken == "too close"
    last = machine.history[-1]
    assert (last.stage, last.reached, last.why, last.t_exit) == ("b", False, "too close", 0.33)


def test_a_guard_that_holds_leaves_the_verdict_to_the_stages() -> None:
    machine = StageMachine([_stage("a", 0.2), _stage("b", 0.5)], guards=(lambda o: None,))
    for i in range(7):
        machine.update(_obs(i * 0.1))
    assert machine.succeeded and machine.broken is None and all(t.why == "" for t in machine.history)
