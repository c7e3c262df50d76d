"""Golden values of every constraint template (Eq. 14-19 and the relational ones) on hand-made features."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from pydantic import TypeAdapter, ValidationError

from kintsugi.taskgraph.constraints import TEMPLATES, Constraint
from kintsugi.taskgraph.features import ArmState, Features, ObjectState

C = TypeAdapter(Constraint)


def make(**data):
    return C.validate_python(data)


@dataclass
class ForeignObject:
    """Stands in for perception's ObjectFeatures: numpy arrays and extra attributes."""

    centroid: np.ndarray
    axis: np.ndarray
    n_points: int
    top: np.ndarray
    upright: bool = True
    extremes: dict | None = None
    extent: tuple | None = None


def tilted(deg: float) -> tuple[float, float, float]:
    r = math.radians(deg)
    return (0.0, math.sin(r), math.cos(r))


C30, S30 = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
F = Features(
    objects={
        "cup": ObjectState(centroid=(0.10, 0.0, 0.05), axis=(0.0, 0.0, -1.0), n_points=400),
        "bottle": ForeignObject(np.array([0.0, 0.0, 0.10]), np.array(tilted(30.0)), 20, np.array([0.0, 0.0, 0.25])),
        # A spoon lying along y, its wide head (the axis end nearer the centroid) towards +y.
        "spoon": ForeignObject(np.array([0.4, 0.02, 0.01]), np.array([0.0, 1.0, 0.0]), 300, np.array([0.4, 0.02, 0.02]),
                               upright=False, extremes={"axis_pos": (0.4, 0.08, 0.01), "axis_neg": (0.4, -0.10, 0.01)}),
        # A tray turned 30 deg, 22 x 16 cm; a capsule in its corner, one beyond its end; a round bin standing.
        "tray": ForeignObject(np.array([0.5, 0.0, 0.01]), np.array([C30, S30, 0.0]), 900, np.array([0.5, 0.0, 0.02]),
                              upright=False, extent=(0.22, 0.16, 0.02)),
        "corner": ObjectState(centroid=(0.5 + 0.09 * C30 - 0.06 * S30, 0.09 * S30 + 0.06 * C30, 0.02)),
        "beyond": ObjectState(centroid=(0.5 - 0.13 * C30, -0.13 * S30, 0.02)),
        "bin": ForeignObject(np.array([0.0, 0.3, 0.05]), np.array([0.0, 0.0, 1.0]), 900, np.array([0.0, 0.3, 0.1]),
                             extent=(0.1, 0.08, 0.08)),
        "in_bin": ObjectState(centroid=(0.03, 0.33, 0.02)),
    },
    arms={"right": ArmState(eef=(0.0, 0.0, 0.30), opening=0.004, closed=True, touching=frozenset({"bottle"}))},
)

GOLDEN = [
    # Eq. 14: drift of the cup centroid from a reference.
    ({"kind": "drift", "point": {"entity": "cup"}, "ref": [0.0, 0.0, 0.05], "tol": 0.03}, 0.07),
    ({"kind": "drift", "point": {"entity": "cup"}, "ref": [0.1, 0.0, 0.9], "tol": 0.03, "axes": "xy"}, -0.03),
    ({"kind": "drift", "point": {"entity": "cup", "offset": [0.0, 0.0, 0.05]}, "ref": [0.1, 0.0, 0.0], "tol": 0.0}, 0.10),
    # Eq. 15: angle between principal axis and gravity; the axis has no sign.
    ({"kind": "upright", "object": "bottle", "tol_deg": 10}, 20.0),
    ({"kind": "upright", "object": "cup", "tol_deg": 10}, -10.0),
    ({"kind": "tilted", "object": "bottle", "min_deg": 60}, 30.0),
    # Eq. 16-17: fingers closed past the object's width; object far from the gripper.
    ({"kind": "not_grasped", "arm": "right", "min_opening": 0.01}, 0.006),
    ({"kind": "detached", "arm": "right", "object": "bottle", "tol": 0.08}, 0.12),
    # Eq. 18: too few points.
    ({"kind": "visibility", "object": "bottle", "n_min": 50}, 30.0),
    ({"kind": "visibility", "object": "cup", "n_min": 50}, -350.0),
    ({"kind": "visibility", "object": "lost", "n_min": 50}, 50.0),
    # Eq. 19: lateral misalignment (xy by default); near is full 3-D by default.
    ({"kind": "misaligned", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "tol": 0.02}, 0.08),
    ({"kind": "near", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "tol": 0.02}, math.hypot(0.1, 0.05) - 0.02),
    ({"kind": "near", "a": {"entity": "right"}, "b": {"entity": "bottle", "feature": "top"}, "tol": 0.0}, 0.05),
    # above: a at least min_gap over b.
    ({"kind": "above", "a": {"entity": "right"}, "b": {"entity": "bottle", "feature": "top"}, "min_gap": 0.02}, -0.03),
    ({"kind": "above", "a": {"entity": "cup"}, "b": {"entity": "bottle"}}, 0.05),
    # in_region: largest excursion outside the box, negative margin inside.
    ({"kind": "in_region", "point": {"entity": "cup"}, "lo": [0.0, -0.1, 0.0], "hi": [0.3, 0.1, 0.2]}, -0.05),
    ({"kind": "in_region", "point": {"entity": "cup"}, "lo": [0.12, -0.1, 0.0], "hi": [0.3, 0.1, 0.2]}, 0.02),
    ({"kind": "touching", "arm": "right", "object": "bottle"}, -1.0),
    ({"kind": "touching", "arm": "right", "object": "cup"}, 1.0),
    ({"kind": "touching", "arm": "right", "object": "bottle", "expect": False}, 1.0),
    # heading: the lying spoon's head points +y (90 deg); off by |wrap(90 - yaw)| minus the tolerance.
    ({"kind": "heading", "object": "spoon", "yaw_deg": 90.0, "tol_deg": 20.0}, -20.0),
    ({"kind": "heading", "object": "spoon", "yaw_deg": -90.0, "tol_deg": 20.0}, 160.0),
    ({"kind": "heading", "object": "spoon", "yaw_deg": 0.0, "tol_deg": 15.0}, 75.0),
    # within: the excursion beyond the footprint's half length / half width in the container's own frame. The
    # corner is inside (a circle of the tray's half width would leave it 2.8 cm out); margin moves the rim in.
    ({"kind": "within", "point": {"entity": "corner"}, "container": "tray"}, -0.02),
    ({"kind": "within", "point": {"entity": "corner"}, "container": "tray", "margin": 0.01}, -0.01),
    ({"kind": "within", "point": {"entity": "beyond"}, "container": "tray"}, 0.02),
    ({"kind": "within", "point": {"entity": "in_bin"}, "container": "bin"}, math.hypot(0.03, 0.03) - 0.04),
    # offset: a - b inside a box (left_of, a stack's gap); spacing: a horizontal distance within a band (beside).
    ({"kind": "offset", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "lo": [0.05, -0.01, -1.0],
      "hi": [0.2, 0.01, 1.0]}, -0.01),
    ({"kind": "offset", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "lo": [0.12, -0.01, -1.0],
      "hi": [0.2, 0.01, 1.0]}, 0.02),
    ({"kind": "spacing", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "min_m": 0.08, "max_m": 0.25}, -0.02),
    ({"kind": "spacing", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "min_m": 0.12, "max_m": 0.25}, 0.02),
    ({"kind": "spacing", "a": {"entity": "cup"}, "b": {"entity": "bottle"}, "max_m": 0.07}, 0.03),
]


def test_heading_of_a_held_object_is_undecided():
    held = Features(objects=dict(F.objects), arms={"right": ArmState(eef=(0.4, 0.0, 0.1), closed=True,
                                                                      touching=frozenset({"spoon"}))})
    assert math.isnan(make(kind="heading", object="spoon", yaw_deg=90.0, tol_deg=20.0).evaluate(held))


@pytest.mark.parametrize("data,expected", GOLDEN, ids=[f"{d['kind']}-{i}" for i, (d, _) in enumerate(GOLDEN)])
def test_golden(data, expected):
    assert make(**data).evaluate(F) == pytest.approx(expected, abs=1e-9)


def test_every_template_has_a_golden_case():
    assert {t.model_fields["kind"].default for t in TEMPLATES} == {d["kind"] for d, _ in GOLDEN}


@pytest.mark.parametrize("data", [
    {"kind": "drift", "point": {"entity": "lost"}, "ref": [0, 0, 0], "tol": 0.1},
    {"kind": "upright", "object": "lost", "tol_deg": 5},
    {"kind": "detached", "arm": "left", "object": "cup", "tol": 0.1},
    {"kind": "misaligned", "a": {"entity": "cup"}, "b": {"entity": "cup", "feature": "missing_attr"}, "tol": 0.1},
    {"kind": "drift", "point": {"entity": "cup"}, "tol": 0.1},  # ref not latched yet
    {"kind": "within", "point": {"entity": "corner"}, "container": "cup"},  # no perceived extent
])
def test_missing_inputs_read_nan(data):
    assert math.isnan(make(**data).evaluate(F))


def test_zero_axis_reads_nan():
    f = Features(objects={"cup": ObjectState(centroid=(0, 0, 0), axis=(0.0, 0.0, 0.0))})
    assert math.isnan(make(kind="upright", object="cup", tol_deg=5).evaluate(f))


def test_drift_latches_reference_at_bind():
    c = make(kind="drift", point={"entity": "cup"}, tol=0.03)
    assert not c.bound
    b = c.bind(F)
    assert b.bound and b.ref == pytest.approx((0.10, 0.0, 0.05))
    moved = Features(objects={"cup": ObjectState(centroid=(0.10, 0.05, 0.05))})
    assert b.evaluate(moved) == pytest.approx(0.02)
    assert b.bind(moved) is b  # an explicit reference is never overwritten


@pytest.mark.parametrize("data", [
    {"kind": "drift", "point": {"entity": "cup"}, "tol": float("nan")},
    {"kind": "drift", "point": {"entity": "cup"}, "tol": float("inf")},
    {"kind": "drift", "point": {"entity": "cup"}, "tol": -0.1},
    {"kind": "drift", "point": {"entity": "cup"}, "tol": True},
    {"kind": "drift", "point": {"entity": "cup"}, "tol": "0.1"},
    {"kind": "drift", "point": {"entity": "cup"}, "tol": 0.1, "code": "import os"},
    {"kind": "drift", "point": {"entity": "cup", "feature": "__class__"}, "tol": 0.1},
    {"kind": "upright", "object": "cup", "tol_deg": 0},
    {"kind": "visibility", "object": "cup", "n_min": 2.5},
    {"kind": "in_region", "point": {"entity": "cup"}, "lo": [1, 0, 0], "hi": [0, 1, 1]},
    {"kind": "python", "source": "lambda f: 0"},
])
def test_bad_templates_rejected(data):
    with pytest.raises(ValidationError):
        make(**data)


def test_reads_perception_object_features():
    """The perception package's ObjectFeatures plugs in as is: extremes by name, None when not visible."""
    from kintsugi.perception.features import ObjectFeatures

    seen = ObjectFeatures(name="bottle", visible=True, n_points=300, fit="primitive", centroid=(0.0, 0.0, 0.1),
                          axis=tilted(30.0), extremes={"top": (0.0, 0.0, 0.2), "bottom": (0.0, 0.0, 0.0),
                                                       "axis_pos": (0.0, 0.0, 0.2), "axis_neg": (0.0, 0.0, 0.0)})
    lost = ObjectFeatures(name="bottle", visible=False, n_points=0, fit="raw")
    arm = {"right": ArmState(eef=(0.0, 0.0, 0.3))}
    f, f_lost = Features(objects={"bottle": seen}, arms=arm), Features(objects={"bottle": lost}, arms=arm)
    cases = [
        ({"kind": "upright", "object": "bottle", "tol_deg": 10}, 20.0),
        ({"kind": "near", "a": {"entity": "right"}, "b": {"entity": "bottle", "feature": "top"}, "tol": 0.0}, 0.1),
        ({"kind": "near", "a": {"entity": "right"}, "b": {"entity": "bottle", "along": 0.75}, "tol": 0.0}, 0.15),
        ({"kind": "detached", "arm": "right", "object": "bottle", "tol": 0.05}, 0.15),
    ]
    for data, expected in cases:
        c = make(**data)
        assert c.evaluate(f) == pytest.approx(expected), data
        assert math.isnan(c.evaluate(f_lost)), data
    assert make(kind="visibility", object="bottle", n_min=10).evaluate(f_lost) == 10.0


def test_point_takes_feature_or_along_not_both():
    with pytest.raises(ValidationError, match="either"):
        make(kind="near", a={"entity": "cup", "feature": "top", "along": 0.5}, b={"entity": "cup"}, tol=0.1)
