"""The three declared contact tasks (slide-puck, roll-cylinder, push-around): their scenes, and their scorers judged
on real physics — a plain scripted push (servo targets, no planner) solves the first two, a straight push jams on the
post of the third; an object put on the disc the wrong way (carried, dragged, through the post) fails."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import numpy as np
import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.worlds.contact.robot import ContactRobot

load_builtins()
NEW = ("slide-puck", "roll-cylinder", "push-around")


def _episode(task: str, seed: int):  # noqa: ANN202
    t = TASKS.get(task).factory()
    cfg = t.config({})
    world, scorer, setup = t.build(cfg, "all", seed)
    return t, world, scorer, setup


def _push_onto_goal(world, scorer, setup, obj: str, height: float) -> None:  # noqa: ANN001
    """Fingers closed, from behind the object along the line to the disc, stopping short of it, then withdraw."""
    robot = ContactRobot(world, watchers=[scorer.watch])
    p, m = setup.scene.start[obj], next(iter(setup.scene.markers.values()))
    half = setup.scene.geometry[obj].parts[0].half[0]
    d = np.array([m.x - p.x, m.y - p.y])
    d /= np.linalg.norm(d)
    start = np.array([p.x, p.y]) - d * (half + 0.03)
    stop = np.array([m.x, m.y]) - d * (half + 0.006)
    robot.act(np.array([*start, 0.08, 0, 0]), 1.0)
    robot.act(np.array([*start, height, 0, 0]), 1.0)
    for k in range(1, 41):
        robot.act(np.array([*(start + (stop - start) * k / 40), height, 0, 0]), 0.1)
    robot.act(np.array([*(stop - d * 0.04), height, 0, 0]), 0.5)
    robot.act(np.array([*(stop - d * 0.04), 0.12, 0, 0]), 1.5)


def _teleport(world, scorer, obj: str, xyz, quat=(1.0, 0.0, 0.0, 0.0)) -> None:  # noqa: ANN001
    a = world.layout.obj_qpos[obj]
    world.data.qpos[a:a + 3], world.data.qpos[a + 3:a + 7] = xyz, quat
    world.data.qvel[world.layout.obj_dof[obj]:world.layout.obj_dof[obj] + 6] = 0.0
    world.step(1)
    scorer.watch(world)


def _settle(world, scorer, seconds: float = 1.0) -> None:  # noqa: ANN001
    for _ in range(int(seconds / 0.01)):
        world.step(5)
        scorer.watch(world)


def test_the_new_tasks_are_registered_run_by_coral_and_declare_shapes_beyond_boxes() -> None:
    shapes = {}
    for name in NEW:
        t, world, _, setup = _episode(name, 0)
        assert t.reference_method == "coral" and t.default_method == "coral"  # no hand-written expert needed
        obj = t.spec.target
        geo = setup.scene.geometry[obj]
        shapes[name] = (geo.shape, geo.parts[0].axis, bool(geo.label), bool(geo.material))
        assert list(setup.scene.markers) == ["goal"] and setup.scene.markers["goal"].label
        assert all(w in t.spec.instruction.lower() for w in geo.label.split())  # the instruction names its label
        world.close()
    assert shapes == {"slide-puck": ("cylinder", "z", True, True), "roll-cylinder": ("cylinder", "y", True, True),
                      "push-around": ("box", "z", True, True)}
    _, _, _, setup = _episode("slide-puck", 0)
    cfg = TASKS.get("slide-puck").factory().config({})
    assert 2 * setup.scene.geometry["puck"].parts[0].radius > cfg.effector.max_opening_m  # too wide to be picked


def test_slide_puck_scripted_push_succeeds_and_a_carried_puck_fails() -> None:
    _, world, scorer, setup = _episode("slide-puck", 1)
    _push_onto_goal(world, scorer, setup, "puck", 0.012)
    ok, details = scorer.finish(world)
    assert ok, details
    assert details.max_lift_m < 0.002 and details.tilt_deg < 2
    # the same end, but the puck was lifted on the way: carried, not slid
    _, world, scorer, setup = _episode("slide-puck", 1)
    m, rest = setup.scene.markers["goal"], setup.scene.geometry["puck"].rest_z
    _teleport(world, scorer, "puck", (m.x, m.y, rest + 0.05))
    _teleport(world, scorer, "puck", (m.x, m.y, rest))
    _settle(world, scorer)
    ok, details = scorer.finish(world)
    assert not ok and details.on_goal and details.max_lift_m > 0.04


def test_roll_cylinder_scripted_push_rolls_it_and_a_dragged_cylinder_fails() -> None:
    _, world, scorer, setup = _episode("roll-cylinder", 3)
    r = setup.scene.geometry["cylinder"].parts[0].radius
    _push_onto_goal(world, scorer, setup, "cylinder", 1.5 * r)  # above its axis: it rolls
    ok, details = scorer.finish(world)
    assert ok, details
    assert details.roll_deg > 300
    # put on the disc without turning about its axis: dragged, not rolled
    _, world, scorer, setup = _episode("roll-cylinder", 3)
    m = setup.scene.markers["goal"]
    _teleport(world, scorer, "cylinder", (m.x, m.y, r))
    _settle(world, scorer)
    ok, details = scorer.finish(world)
    assert not ok and details.on_goal and details.roll_deg < 5
    # on the disc but stood on its end: no longer lying
    _, world, scorer, setup = _episode("roll-cylinder", 3)
    half_len = setup.scene.geometry["cylinder"].parts[0].half[1]
    _teleport(world, scorer, "cylinder", (m.x, m.y, half_len), (0.7071068, 0.7071068, 0.0, 0.0))
    _settle(world, scorer)
    assert not scorer.finish(world)[0]


def test_push_around_a_straight_push_jams_on_the_post_and_one_round_it_is_judged_on_the_disc() -> None:
    _, world, scorer, setup = _episode("push-around", 3)
    _push_onto_goal(world, scorer, setup, "box", 0.02)
    ok, details = scorer.finish(world)
    assert not ok and "post" in details.touched and not details.on_goal
    _, world, scorer, setup = _episode("push-around", 3)
    m, post, rest = setup.scene.markers["goal"], setup.scene.fixtures["post"], setup.scene.geometry["box"].rest_z
    side = 0.09 if post.pos[1] <= 0 else -0.09
    for x in np.linspace(setup.scene.start["box"].x, m.x, 30):  # slid round the post (never lifted)
        _teleport(world, scorer, "box", (x, side * np.sin(np.pi * (x - setup.scene.start["box"].x)
                                                         / (m.x - setup.scene.start["box"].x)), rest))
    _teleport(world, scorer, "box", (m.x, m.y, rest))
    _settle(world, scorer)
    ok, details = scorer.finish(world)
    assert ok, details
    # straight through the post's place: touched it
    _, world, scorer, setup = _episode("push-around", 3)
    _teleport(world, scorer, "box", (post.pos[0], post.pos[1], rest))
    _teleport(world, scorer, "box", (m.x, m.y, rest))
    _settle(world, scorer)
    ok, details = scorer.finish(world)
    assert not ok and details.touched == ["post"]


@pytest.mark.parametrize("task", NEW)
def test_a_method_sees_labels_and_shapes_but_no_physics_ranges(task: str) -> None:
    from kintsugi.core.record import ReasonerSettings

    t = TASKS.get(task).factory()
    episode = t.episode(t.config({}), "default", "all", 2)
    try:
        ctx = episode.context(frozenset({"system-c"}), ReasonerSettings(), 2)
        section = getattr(ctx.cfg, t.spec.target)
        assert section.mass_kg is None and section.friction is None and section.size_m is None
        assert ctx.oracle_physics is None and ctx.seed is None
        geo = ctx.known.geometry[t.spec.target]
        assert geo.label and geo.material and "mass" not in ctx.known.model_dump_json()
    finally:
        episode.close()
