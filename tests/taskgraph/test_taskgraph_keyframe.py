"""Node synthesis (Eq. 9): dual annealing then SLSQP finds a keyframe that satisfies the node's constraints
near the reference, respects soft terms, and reports an infeasible node with the solver's message."""

from __future__ import annotations

import numpy as np
from pydantic import TypeAdapter

from kintsugi.taskgraph.constraints import Constraint
from kintsugi.taskgraph.features import ArmState, Features, ObjectState
from kintsugi.taskgraph.keyframe import solve_keyframe

C = TypeAdapter(Constraint)
CUP = ObjectState(centroid=(0.5, 0.0, 0.05))
BOUNDS = [(-1.0, 1.0), (-1.0, 1.0), (0.0, 1.0)]


def hand_at(x):
    return Features(objects={"cup": CUP}, arms={"right": ArmState(eef=tuple(x))})


def test_keyframe_meets_constraints_closest_to_the_reference() -> None:
    near = C.validate_python({"kind": "near", "a": {"entity": "right"}, "b": {"entity": "cup"}, "tol": 0.05})
    above = C.validate_python({"kind": "above", "a": {"entity": "right"}, "b": {"entity": "cup"}, "min_gap": 0.02})
    kf = solve_keyframe([near, above], hand_at, reference=np.array([0.2, 0.3, 0.3]), bounds=BOUNDS)
    assert kf.ok, kf.message
    assert np.linalg.norm(kf.x - np.array([0.5, 0.0, 0.05])) <= 0.05 + 1e-3 and kf.x[2] >= 0.07 - 1e-3
    # the closest feasible point to the reference lies on the ball's surface, towards the reference
    d = np.array([0.2, 0.3, 0.3]) - np.array([0.5, 0.0, 0.05])
    expect = np.array([0.5, 0.0, 0.05]) + 0.05 * d / np.linalg.norm(d)
    assert np.linalg.norm(kf.x - expect) < 0.01


def test_soft_terms_and_consistency_shape_the_solution() -> None:
    wall = lambda x: 1e3 * max(0.0, x[1] - 0.0) ** 2  # noqa: E731 - stay at y <= 0
    kf = solve_keyframe([], hand_at, reference=np.array([0.3, 0.2, 0.3]), bounds=BOUNDS, penalties=[wall])
    assert kf.x[1] < 0.01
    kf2 = solve_keyframe([], hand_at, reference=np.array([0.3, 0.0, 0.3]), bounds=BOUNDS,
                         last=np.array([0.3, -0.2, 0.3]), consistency_weight=1.0)
    assert -0.11 < kf2.x[1] < -0.09  # halfway between the reference and the last solution


def test_an_infeasible_node_is_reported_not_faked() -> None:
    far = C.validate_python({"kind": "above", "a": {"entity": "right"}, "b": {"entity": "cup"}, "min_gap": 5.0})
    kf = solve_keyframe([far], hand_at, reference=np.array([0.5, 0.0, 0.5]), bounds=BOUNDS)
    assert not kf.ok and "no feasible keyframe" in kf.message and "above" in kf.message
    assert kf.violation > 3.0


def test_the_solver_is_deterministic() -> None:
    near = C.validate_python({"kind": "near", "a": {"entity": "right"}, "b": {"entity": "cup"}, "tol": 0.02})
    a = solve_keyframe([near], hand_at, reference=np.array([0.0, 0.0, 0.5]), bounds=BOUNDS)
    b = solve_keyframe([near], hand_at, reference=np.array([0.0, 0.0, 0.5]), bounds=BOUNDS)
    assert np.array_equal(a.x, b.x)
