"""Each registered tabletop task's instruction is the only thing AgentChord reads: over the task's first
observation it reads as exactly the task's ground-truth goal (which only the scorer uses), or, for a task the
action library cannot do (fold-towel), it is refused at compile time with a message naming what is missing."""

from __future__ import annotations

import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.methods.agentchord.compile import labelled, task_regions
from kintsugi.methods.agentchord.domain import TABLETOP_DOMAIN
from kintsugi.methods.agentchord.instruction import scene_of
from kintsugi.methods.agentchord.language import NotUnderstood
from kintsugi.methods.agentchord.observe import seen_objects
from kintsugi.methods.agentchord.reading import read

load_builtins()
REFUSED = {"fold-towel": "parts of an object"}
WORDS = frozenset({p.name for p in TABLETOP_DOMAIN.predicates} | set(TABLETOP_DOMAIN.aliases))


def _reading(name: str):  # noqa: ANN202
    from kintsugi.worlds.tabletop.robot import TabletopRobot

    t = TASKS.get(name).factory()
    cfg = t.config({})
    world, *_ = t.build(cfg, "none", 0)
    try:
        obs = TabletopRobot(world).observation(images=False)
    finally:
        world.close()
    scene = scene_of(labelled(seen_objects(obs.objects), t.spec, cfg), ["left", "right"], task_regions(t.spec, cfg),
                     TABLETOP_DOMAIN)
    return t.spec, lambda: read(t.spec.instruction, scene, WORDS)


@pytest.mark.parametrize("name", sorted(e.name for e in TASKS if "system-b" in e.tags))
def test_the_instruction_reads_as_the_scorers_goal(name: str) -> None:
    spec, reading = _reading(name)
    if name in REFUSED:
        with pytest.raises(NotUnderstood, match=REFUSED[name]):
            reading()
        return
    assert sorted(reading().goal) == sorted(spec.goal)


def test_fold_towel_is_refused_at_compile_time_not_with_a_parser_error() -> None:
    from kintsugi.core.record import ReasonerSettings
    from kintsugi.methods.agentchord.show import compile_for_task

    with pytest.raises(NotUnderstood, match="not understood: 'its two bottom corners.*parts of an object"):
        compile_for_task("fold-towel", "none", 0, {}, ReasonerSettings())


def test_the_tasks_own_goal_never_reaches_the_method() -> None:
    """Poisoned truth: with the task's goal predicates replaced by nonsense, AgentChord composes the same graph
    (it reads the instruction only)."""
    from dataclasses import replace

    from kintsugi.core.record import ReasonerSettings
    from kintsugi.methods.agentchord.compile import compile_graph
    from kintsugi.reasoning import make_reasoner
    from kintsugi.worlds.tabletop.robot import TabletopRobot

    t = TASKS.get("pour-single").factory()
    cfg = t.config({})
    world, *_ = t.build(cfg, "none", 0)
    try:
        obs = TabletopRobot(world).observation(images=False)
    finally:
        world.close()
    poisoned = replace(t.spec, goal=("poured(cup, bottle)", "not upright(cup)", "held_up(bottle)"))
    runs = [compile_graph(make_reasoner(ReasonerSettings()), s, obs, cfg=cfg) for s in (t.spec, poisoned)]
    assert runs[0].composer.goal == runs[1].composer.goal and sorted(runs[0].composer.goal) == sorted(t.spec.goal)
    assert runs[0].composer.edge_operators == runs[1].composer.edge_operators
    assert len(runs[0].graph.edges) == len(runs[1].graph.edges)
