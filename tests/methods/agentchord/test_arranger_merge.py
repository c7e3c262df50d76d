"""The arranger's shortcut for a failure that leaves a nominal node's facts (plan to the failed edge's target
only, not to every later node) gives the same recovery branches as the full merge search, on every task."""

from __future__ import annotations

import json

import pytest

import kintsugi.methods.agentchord.merging as merging
from kintsugi.methods.agentchord.compile import compile_graph
from kintsugi.reasoning import make_reasoner
from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import TASKS
from kintsugi.worlds.tabletop.robot import TabletopRobot
from kintsugi.core.record import ReasonerSettings

TASK_NAMES = ("pour-single", "pour-dual", "rearrange-table", "handover-block", "coffee-tray")


def _branches(name: str) -> list[str]:
    load_builtins()
    task = next(e for e in TASKS if e.name == name).factory()
    cfg = task.config({})
    world, *_ = task.build(cfg, "none", 0)
    obs = TabletopRobot(world).observation(images=False)
    graph = compile_graph(make_reasoner(ReasonerSettings()), task.spec, obs, cfg=cfg).graph
    return sorted(json.dumps([e.id, e.source, e.target, [a.model_dump(mode="json") for a in e.actions],
                              [m.model_dump(mode="json") for m in e.monitors]], sort_keys=True) for e in graph.edges)


@pytest.mark.parametrize("name", TASK_NAMES)
def test_the_nominal_shortcut_keeps_every_branch(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    taken: list[str] = []
    shortcut = merging._nominal_merge

    def counted(*args):  # noqa: ANN002, ANN202
        found = shortcut(*args)
        if found is not None:
            taken.append(found[0])
        return found

    monkeypatch.setattr(merging, "_nominal_merge", counted)
    fast = _branches(name)
    assert taken, f"{name}: no failure left a nominal node's facts (the shortcut is untested here)"
    monkeypatch.setattr(merging, "_nominal_merge", lambda *args: None)
    assert _branches(name) == fast
