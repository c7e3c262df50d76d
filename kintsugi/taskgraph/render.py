"""Pictures of a task graph: a DOT file for graphviz users and a PNG drawn with matplotlib (Agg).

Nominal elements are solid blue, recovery elements dashed pink (the paper's Fig. 3 colours);
start and goal have a double border. The layout is layered: nominal nodes by topological
generation of the nominal graph (cycles collapsed), recovery nodes half a layer after their
failure context, below the nominal rows.
"""

from __future__ import annotations

from pathlib import Path

import networkx as nx

from kintsugi.taskgraph.model import Edge, TaskGraph

NOMINAL = "#1f6fb4"
RECOVERY = "#d6336c"


def _q(text: str) -> str:
    """A DOT double-quoted string."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _edge_label(e: Edge) -> str:
    acts = ", ".join(a.name for a in e.actions)
    lines = [f"{e.id}: {acts} ({e.cost:g})"]
    lines += [f"{m.id}: {m.failure_mode} -> {m.recovery or 'detect only'}" for m in e.monitors]
    return "\n".join(lines)


def to_dot(graph: TaskGraph) -> str:
    """The graph as DOT text (render with `dot -Tpng`)."""
    out = [f"digraph {_q(graph.task or 'taskgraph')} {{", "  rankdir=LR;",
           '  node [shape=box, style="rounded", fontname="Helvetica"];', '  edge [fontname="Helvetica", fontsize=10];']
    for n in graph.nodes:
        colour = NOMINAL if n.kind == "nominal" else RECOVERY
        style = "rounded" if n.kind == "nominal" else "rounded,dashed"
        label = n.id + (f"\n{n.description}" if n.description else "")
        extra = ", peripheries=2" if n.id in (graph.start, graph.goal) else ""
        out.append(f"  {_q(n.id)} [label={_q(label)}, color={_q(colour)}, style={_q(style)}{extra}];")
    for e in graph.edges:
        colour = NOMINAL if e.kind == "nominal" else RECOVERY
        style = "solid" if e.kind == "nominal" else "dashed"
        out.append(f"  {_q(e.source)} -> {_q(e.target)} [label={_q(_edge_label(e))}, color={_q(colour)}, style={style}];")
    out.append("}")
    return "\n".join(out) + "\n"


def layout(graph: TaskGraph) -> dict[str, tuple[float, float]]:
    """Layered positions: x = generation along the nominal graph, y spreads each layer."""
    nom = nx.DiGraph()
    nom.add_nodes_from(n.id for n in graph.nodes if n.kind == "nominal")
    nom.add_edges_from((e.source, e.target) for e in graph.edges if e.kind == "nominal" and e.source != e.target)
    dag = nx.condensation(nom)
    layer: dict[str, int] = {}
    for i, generation in enumerate(nx.topological_generations(dag)):
        for c in generation:
            for n in dag.nodes[c]["members"]:
                layer[n] = i
    pos: dict[str, tuple[float, float]] = {}
    by_layer: dict[int, list[str]] = {}
    for n in graph.nodes:  # declaration order keeps the picture stable
        if n.kind == "nominal":
            by_layer.setdefault(layer[n.id], []).append(n.id)
    for x, members in by_layer.items():
        for j, n in enumerate(members):
            pos[n] = (float(x), (len(members) - 1) / 2.0 - j)
    low = min((y for _, y in pos.values()), default=0.0)
    depth: dict[float, int] = {}
    rec_edges = [e for e in graph.edges if e.kind == "recovery"]
    pending = [n.id for n in graph.nodes if n.kind == "recovery"]
    while pending:  # place a recovery node after its already placed predecessor
        progressed = False
        for r in list(pending):
            src = next((e.source for e in rec_edges if e.target == r and e.source in pos), None)
            if src is None:
                continue
            x = pos[src][0] + 0.5
            depth[x] = depth.get(x, 0) + 1
            pos[r] = (x, low - depth[x])
            pending.remove(r)
            progressed = True
        if not progressed:  # not reachable from a placed node: park them at the left
            for k, r in enumerate(pending):
                pos[r] = (-0.5, low - 1 - k)
            break
    return pos


def write_graph_picture(graph: TaskGraph, path: str | Path, dpi: int = 120) -> Path:
    """Draw the graph to a PNG file (no display needed); returns the path written."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch

    pos = layout(graph)
    xs = [p[0] for p in pos.values()]
    ys = [p[1] for p in pos.values()]
    fig = Figure(figsize=(max(6.0, 2.6 * (max(xs) - min(xs) + 1)), max(3.5, 1.6 * (max(ys) - min(ys) + 1))))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    g = graph.nx
    for kind, colour, style in (("nominal", NOMINAL, "solid"), ("recovery", RECOVERY, "dashed")):
        ids = [n.id for n in graph.nodes if n.kind == kind]
        if ids:
            widths = [3.0 if n in (graph.start, graph.goal) else 1.5 for n in ids]
            coll = nx.draw_networkx_nodes(g, pos, nodelist=ids, ax=ax, node_color="white", edgecolors=colour,
                                          linewidths=widths, node_size=2200, node_shape="s")
            coll.set_linestyle(style)
    for kind, colour, style, rad in (("nominal", NOMINAL, "solid", 0.0), ("recovery", RECOVERY, "dashed", 0.25)):
        edges = [(e.source, e.target) for e in graph.edges if e.kind == kind and e.source != e.target]
        for e in graph.edges:  # a retry loop: a small arc over its node
            if e.kind == kind and e.source == e.target:
                x, y = pos[e.source]
                ax.add_patch(FancyArrowPatch((x + 0.06, y + 0.24), (x - 0.06, y + 0.24), color=colour,
                                             linestyle=style, connectionstyle="arc3,rad=1.6", arrowstyle="-|>",
                                             mutation_scale=12, linewidth=1.6))
        if edges:
            nx.draw_networkx_edges(
                nx.DiGraph(edges), pos, ax=ax, edge_color=colour, style=style, width=1.6, arrowsize=14,
                connectionstyle=f"arc3,rad={rad}", node_size=2200, node_shape="s",
            )
    nx.draw_networkx_labels(g, pos, labels={n.id: n.id for n in graph.nodes}, ax=ax, font_size=8)
    for e in graph.edges:
        (x0, y0), (x1, y1) = pos[e.source], pos[e.target]
        rad = 0.0 if e.kind == "nominal" else 0.25
        # Midpoint of matplotlib's arc3 curve: chord midpoint pushed half the way to its control point.
        x, y = (x0 + x1) / 2 + 0.5 * rad * (y1 - y0), (y0 + y1) / 2 - 0.5 * rad * (x1 - x0)
        if e.source == e.target:
            y += 0.5
        elif e.kind == "nominal":
            y += 0.12
        text = ", ".join(a.name for a in e.actions) + "".join(f"\n! {m.failure_mode}" for m in e.monitors)
        ax.text(x, y, text, fontsize=6, ha="center", va="bottom" if e.kind == "nominal" else "center",
                color=NOMINAL if e.kind == "nominal" else RECOVERY)
    ax.legend(handles=[Line2D([], [], color=NOMINAL, label="nominal"),
                       Line2D([], [], color=RECOVERY, linestyle="--", label="recovery")], loc="upper right", fontsize=8)
    ax.set_title(graph.task or "task graph", fontsize=10)
    ax.set_xlim(min(xs) - 0.6, max(xs) + 0.6)
    ax.set_ylim(min(ys) - 0.6, max(ys) + 0.7)
    ax.set_axis_off()
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=dpi)
    return out
