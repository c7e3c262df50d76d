"""coral's verdict keeps clear of what the instruction forbids touching, over the whole attempt, from what the
robot perceives (`kintsugi.methods.coral.clearance`); a scripted perceived trajectory, no MuJoCo run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from kintsugi.core.errors import ReasoningError
from kintsugi.methods.coral.clearance import MARGIN_M, box_prism, fixture_prism, gap, guards, keep_clear
from kintsugi.methods.mppi.fsm import Stage, StageMachine
from kintsugi.worlds.contact.objects import Fixture, Geometry, Marker, Part, Placement
from kintsugi.worlds.contact.robot import Observation, TrackedObject
from kintsugi.worlds.contact.world import Scene
from tests.methods.coral.language_scenes import scene_request

BOX_HALF = (0.03, 0.035, 0.025)
POST = Fixture(half=(0.02, 0.02, 0.05), pos=(0.1, 0.0, 0.05), label="grey post")
SCENE = Scene(geometry={"box": Geometry(parts=(Part(half=BOX_HALF),), label="red box", colour="red",
                                        material="cardboard")},
              start={"box": Placement(x=-0.02, y=0.0)}, fixtures={"post": POST},
              markers={"goal": Marker(x=0.2, y=0.0, radius=0.035, label="green disc")})
AROUND = "Push the red box onto the green disc without touching the grey post."


def _obs(t: float, objects: dict[str, tuple[float, float, float]]) -> Observation:
    """The robot's observation with each object's tracked (x, y, yaw in degrees), standing on the table."""
    tracked = {k: TrackedObject(pos=np.array([x, y, 0.025]),
                                quat=np.array([math.cos(math.radians(yaw) / 2), 0.0, 0.0,
                                               math.sin(math.radians(yaw) / 2)]),
                                lin_vel=np.zeros(3), ang_vel=np.zeros(3)) for k, (x, y, yaw) in objects.items()}
    return Observation(t=t, ee=np.array([-0.1, 0.0, 0.01, 0.0]), ee_vel=np.zeros(4), fingers=np.zeros(2),
                       finger_vel=np.zeros(2), force=np.zeros(3), torque=np.zeros(3), touch=np.zeros(2),
                       objects=tracked, ctrl=np.zeros(5))


def _path(side_y: float, steps: int = 60) -> list[Observation]:
    """The box pushed round the post to the disc: out to `side_y`, along past the post, back in."""
    corners = [(-0.02, 0.0), (0.02, side_y), (0.18, side_y), (0.2, 0.0)]
    out = []
    for i in range(steps):
        s = 3 * i / (steps - 1)
        k = min(int(s), 2)
        (ax, ay), (bx, by) = corners[k], corners[k + 1]
        out.append(_obs(0.1 * i, {"box": (ax + (bx - ax) * (s - k), ay + (by - ay) * (s - k), 0.0)}))
    return out


def test_the_gap_between_prisms_is_the_footprints_distance_and_the_heights_gap() -> None:
    post = fixture_prism((0.08, -0.02, 0.0), (0.12, 0.02, 0.1))
    beside = box_prism(np.array([0.1, 0.07, 0.025]), np.array([1.0, 0, 0, 0]), BOX_HALF)
    assert gap(beside, post) == pytest.approx(0.07 - 0.035 - 0.02)
    above = box_prism(np.array([0.1, 0.0, 0.2]), np.array([1.0, 0, 0, 0]), BOX_HALF)
    assert gap(above, post) == pytest.approx(0.2 - 0.025 - 0.1)
    on_it = box_prism(np.array([0.1, 0.05, 0.025]), np.array([1.0, 0, 0, 0]), BOX_HALF)
    assert gap(on_it, post) == 0.0
    turned = box_prism(np.array([0.1, 0.08, 0.025]), np.array([math.cos(math.pi / 8), 0, 0, math.sin(math.pi / 8)]),
                       BOX_HALF)  # 45 degrees: its corner reaches down toward the post
    corner = 0.08 - math.hypot(*BOX_HALF[:2]) * math.sin(math.radians(45) + math.atan2(BOX_HALF[1], BOX_HALF[0]))
    assert gap(turned, post) == pytest.approx(corner - 0.02, abs=1e-6)


def test_a_push_that_grazes_the_post_breaks_the_constraint_and_one_that_keeps_clear_does_not() -> None:
    keep = keep_clear(scene_request("around", AROUND), SCENE)
    assert keep.movers == ["box"] and list(keep.fixtures) == ["post"]
    grazing = [keep(o) for o in _path(0.0555)]  # the box's side passes 0.5 mm from the post's
    assert any(grazing)
    first = next(w for w in grazing if w)
    assert first.startswith("box came within") and "post" in first and "forbids touching" in first
    assert not any(keep(o) for o in _path(0.075))  # 20 mm clear at the closest


def test_coming_within_the_margin_breaks_it_touching_says_touched() -> None:
    keep = keep_clear(scene_request("around", AROUND), SCENE)
    side = 0.02 + BOX_HALF[1]
    assert keep(_obs(0.0, {"box": (0.1, side + MARGIN_M + 1e-4, 0.0)})) is None
    assert "came within" in keep(_obs(0.0, {"box": (0.1, side + MARGIN_M - 1e-4, 0.0)}))
    assert "touched post" in keep(_obs(0.0, {"box": (0.1, side - 0.002, 0.0)}))


def test_the_stage_and_the_attempt_fail_where_the_path_broke_the_constraint() -> None:
    def stage(name: str, done_at: float):  # noqa: ANN202
        return lambda obs: Stage(name=name, cost=lambda view: np.zeros(1), done=lambda o: o.t >= done_at)

    keep = keep_clear(scene_request("around", AROUND), SCENE)
    for side, ok in ((0.0555, False), (0.075, True)):
        machine = StageMachine([stage("slide", 3.0), stage("slide-2", 6.0)], guards=(keep,))
        for obs in _path(side, 62):
            machine.update(obs)
            machine.watch(obs)
            if machine.finished:
                break
        assert machine.succeeded is ok
        if not ok:
            assert machine.broken and machine.history[-1].why == machine.broken
            assert not machine.history[-1].reached


def test_every_without_touching_clause_is_kept_and_unknown_names_are_refused() -> None:
    keep = keep_clear(scene_request("around", "Push the cardboard box onto the goal and do not touch the post."),
                      SCENE)
    assert list(keep.fixtures) == ["post"] and keep
    assert not keep_clear(scene_request("around", "Push the red box onto the green disc."), SCENE)
    with pytest.raises(ReasoningError, match="nothing in the scene is 'the blue post'"):
        guards(scene_request("around", "Push the red box onto the green disc without touching the blue post."),
               SCENE)
    with pytest.raises(ReasoningError, match="'cup' is neither a word of the language nor a name in the scene"):
        guards(scene_request("around", "Push the red box onto the green disc without touching the cup."), SCENE)


def test_an_object_to_avoid_is_kept_clear_by_its_tracked_box_with_a_margin_for_each() -> None:
    two = Scene(geometry={n: Geometry(parts=(Part(half=(0.03, 0.035, 0.025)),), label="box", colour=c)
                          for n, c in (("red_box", "red"), ("blue_box", "blue"))},
                start={"red_box": Placement(x=0.03, y=0.08), "blue_box": Placement(x=0.03, y=-0.08)})
    keep = keep_clear(scene_request("two", "Push the blue box 5 cm to the left without touching the red box."), two)
    assert keep.movers == ["blue_box"] and keep.objects == ["red_box"]
    apart = 0.07 + 2 * MARGIN_M
    assert keep(_obs(0.0, {"blue_box": (0.03, 0.0, 0.0), "red_box": (0.03, apart + 1e-4, 0.0)})) is None
    assert "blue_box came within" in keep(_obs(0.0, {"blue_box": (0.03, 0.0, 0.0), "red_box": (0.03, apart - 1e-4, 0.0)}))


def test_the_margin_grows_by_the_path_of_a_hand_within_reach_over_a_tracked_poses_age_and_afresh_per_attempt() -> None:
    keep = keep_clear(scene_request("around", AROUND), SCENE, age_s=0.15)
    at = (0.1, 0.02 + BOX_HALF[1] + MARGIN_M + 0.004, 0.0)  # 4 mm beyond the margin of a still hand
    for i, x in enumerate((0.05, 0.055, 0.06)):  # the hand behind the box pushed 10 mm in 0.1 s: it may be there
        obs = _obs(0.05 * i, {"box": at})
        obs.ee[:3] = (x, at[1], 0.01)
        why = keep(obs)
    assert why is not None and "kept 13 mm clear" in why
    again = keep.fresh()
    assert again(_obs(0.1, {"box": at})) is None
    far = keep.fresh()
    for i, x in enumerate((-0.15, -0.1, -0.05)):  # the hand flying in from home, far from the box, moves nothing
        obs = _obs(0.05 * i, {"box": at})
        obs.ee[:3] = (x, 0.0, 0.15)
        assert far(obs) is None
