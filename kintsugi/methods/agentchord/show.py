"""`kintsugi graph <task>`: compile a tabletop task's graph from its first observation and print it."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from kintsugi.core.errors import ConfigError
from kintsugi.methods.agentchord.compile import Compiled, compile_graph


def compile_for_task(task: str, condition: str, seed: int, overrides: dict, settings: Any) -> Compiled:
    """Build the task's world for (condition, seed), take the first observation, compile (composer, arranger)."""
    from kintsugi.reasoning import make_reasoner
    from kintsugi.reasoning.base import RecordingReasoner
    from kintsugi.core.plugins import load_builtins
    from kintsugi.core.registry import TASKS
    from kintsugi.worlds.tabletop.robot import TabletopRobot

    load_builtins()
    t = TASKS.get(task).factory()
    if not hasattr(t, "spec") or "system-b" not in TASKS.get(task).tags:
        known = ", ".join(e.name for e in TASKS if "system-b" in e.tags)
        raise ConfigError(f"task {task!r} has no task graph: graphs are compiled for the tabletop (system B) "
                          f"tasks: {known}")
    reasoner = RecordingReasoner(make_reasoner(settings))
    cfg = t.config(overrides)
    world, _, _, _ = t.build(cfg, condition, seed)
    try:
        robot = TabletopRobot(world)
        return compile_graph(reasoner, t.spec, robot.observation(images=reasoner.sees_images), cfg=cfg)
    finally:
        world.close()


def print_graph(c: Compiled, console: Console) -> None:
    """Nodes and edges (nominal bold blue, recovery pink), each monitor with its recovery, Eq. 8 verdicts."""
    g = c.graph
    ctg = c.result.cost_to_go
    console.print(f"[bold]{escape(g.task)}[/bold]  start {escape(g.start)} -> goal {escape(g.goal)}; "
                  f"composer {1000 * c.timings_s['composer']:.0f} ms, arranger {1000 * c.timings_s['arranger']:.0f} ms")
    nodes = Table(title="sub-goal nodes")
    for col in ("node", "kind", "cost-to-go", "constraints", "gripper"):
        nodes.add_column(col)
    for n in g.nodes:
        style = "bold #1f6fb4" if n.kind == "nominal" else "#d6336c"
        nodes.add_row(escape(n.id), n.kind, f"{ctg[n.id]:g}", escape(", ".join(k.kind for k in n.constraints)),
                      escape(", ".join(f"{a} {s}" for a, s in n.gripper.items())), style=style)
    console.print(nodes)
    edges = Table(title="transitions")
    for col in ("edge", "from -> to", "actions", "cost", "monitors (failure -> recovery edge)"):
        edges.add_column(col)
    for e in g.edges:
        style = "bold #1f6fb4" if e.kind == "nominal" else "#d6336c"
        mons = "; ".join(f"{m.failure_mode} [{m.check.kind} > {m.margin:g} for {m.window}] -> {m.recovery or 'detect only'}"
                         for m in e.monitors)
        edges.add_row(escape(e.id), escape(f"{e.source} -> {e.target}"), escape(", ".join(a.name for a in e.actions)),
                      f"{e.cost:g}", escape(mons), style=style)
    console.print(edges)
    console.print(f"Eq. 8: {len(c.result.kept)} recovery branches kept, {len(c.result.rejected)} dropped")
    for b in c.result.rejected:
        console.print(f"  dropped {escape(str(b.edge or b.via))}: {escape(b.reason)}")
    console.print(f"arranger: {escape(c.arranger.reasoning)}")
