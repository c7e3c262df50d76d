"""Pictures of a task graph: a DOT file for graphviz users, a PNG drawn with matplotlib (Agg) and an
interactive HTML page (an SVG you can zoom and pan, every box with its details on hover).

Nominal elements are solid blue, recovery elements dashed pink (the paper's Fig. 3 colours); start
and goal have a thick border. The layout is layered from top to bottom: each node's layer is its
longest path from the start over the graph without its back edges (retry loops, returns to an
earlier sub-goal), and each edge's label is a box of its own in the layer between its ends, so no
two boxes (nodes or labels) overlap by construction. Within a layer boxes are ordered by the mean
position of what leads into them, which keeps the nominal path in one column when it can.
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from pathlib import Path
from textwrap import wrap

from kintsugi.taskgraph.model import Edge, Node, TaskGraph

NOMINAL = "#1f6fb4"
RECOVERY = "#d6336c"
FONT_PT = 8.0
CHAR_PT = 0.61 * FONT_PT
"""Width of one character of the monospace font, in points."""
LINE_PT = 1.25 * FONT_PT
PAD_PT = 5.0
GAP_X_PT = 14.0
GAP_Y_PT = 22.0
MAX_LABEL_LINES = 5


@dataclass(frozen=True)
class Box:
    """A node's or an edge label's box, in points: (x, y) its top-left corner, y growing downwards."""

    key: str
    """The node id, or `edge:<edge id>` for an edge's label."""
    lines: tuple[str, ...]
    kind: str
    x: float
    y: float
    w: float
    h: float
    layer: int

    @property
    def centre(self) -> tuple[float, float]:
        return self.x + self.w / 2, self.y + self.h / 2

    def overlaps(self, other: "Box") -> bool:
        return (self.x < other.x + other.w and other.x < self.x + self.w
                and self.y < other.y + other.h and other.y < self.y + self.h)


def _q(text: str) -> str:
    """A DOT double-quoted string."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _edge_label(e: Edge) -> str:
    acts = ", ".join(a.name for a in e.actions)
    lines = [f"{e.id}: {acts} ({e.cost:g})"]
    lines += [f"{m.id}: {m.failure_mode} -> {m.recovery or 'detect only'}" for m in e.monitors]
    return "\n".join(lines)


def to_dot(graph: TaskGraph) -> str:
    """The graph as DOT text (render with `dot -Tpng`), top to bottom."""
    out = [f"digraph {_q(graph.task or 'taskgraph')} {{", "  rankdir=TB;",
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


def _node_lines(n: Node) -> tuple[str, ...]:
    return (n.id, *wrap(n.description, 30)[:2]) if n.description else (n.id,)


def _label_lines(e: Edge) -> tuple[str, ...]:
    lines = [", ".join(a.name for a in e.actions)]
    monitors = [f"! {m.failure_mode}" for m in e.monitors]
    if len(monitors) > MAX_LABEL_LINES - 1:
        monitors = monitors[:MAX_LABEL_LINES - 2] + [f"! +{len(e.monitors) - MAX_LABEL_LINES + 2} more"]
    return tuple(line[:34] for line in lines + monitors)


def _ranks(graph: TaskGraph) -> dict[str, int]:
    """Longest-path rank from the start over the graph without its back edges (found by a DFS)."""
    out: dict[str, list[str]] = {n.id: [] for n in graph.nodes}
    for e in graph.edges:
        if e.source != e.target:
            out[e.source].append(e.target)
    state: dict[str, int] = {}
    forward: set[tuple[str, str]] = set()
    order: list[str] = []
    roots = [graph.start] + [n.id for n in graph.nodes if n.id != graph.start]
    for root in roots:
        if root in state:
            continue
        stack = [(root, iter(out[root]))]
        state[root] = 1
        while stack:
            node, children = stack[-1]
            child = next(children, None)
            if child is None:
                state[node] = 2
                order.append(node)
                stack.pop()
            elif state.get(child) != 1:  # not an edge back to a node on the current path
                forward.add((node, child))
                if child not in state:
                    state[child] = 1
                    stack.append((child, iter(out[child])))
    rank = {n: 0 for n in out}
    for node in reversed(order):  # reverse post-order is a topological order of the forward edges
        for child in out[node]:
            if (node, child) in forward:
                rank[child] = max(rank[child], rank[node] + 1)
    return rank


def boxes(graph: TaskGraph) -> dict[str, Box]:
    """Every node's and edge label's box: node layers at even depths, each label one below its source."""
    rank = _ranks(graph)
    items: list[tuple[str, tuple[str, ...], str, int, list[str]]] = []
    for n in graph.nodes:
        ins = [e.source for e in graph.edges if e.target == n.id and rank[e.source] < rank[n.id]]
        items.append((n.id, _node_lines(n), n.kind, 2 * rank[n.id], [f"edge:{e.id}" for e in graph.edges
                                                                      if e.target == n.id and e.source in ins]))
    for e in graph.edges:
        items.append((f"edge:{e.id}", _label_lines(e), e.kind, 2 * rank[e.source] + 1, [e.source]))
    layers: dict[int, list] = {}
    for item in items:
        layers.setdefault(item[3], []).append(item)
    placed: dict[str, Box] = {}
    y = 0.0
    for layer in sorted(layers):
        members = layers[layer]

        def mean_x(item: tuple) -> float:
            xs = [placed[p].centre[0] for p in item[4] if p in placed]
            return sum(xs) / len(xs) if xs else 0.0

        members.sort(key=lambda it: (mean_x(it), it[2] != "nominal"))  # stable: declaration order on ties
        x, height = 0.0, 0.0
        for key, lines, kind, _, _ in members:
            w = max(len(s) for s in lines) * CHAR_PT + 2 * PAD_PT
            h = len(lines) * LINE_PT + 2 * PAD_PT
            placed[key] = Box(key, lines, kind, x, y, w, h, layer)
            x += w + GAP_X_PT
            height = max(height, h)
        y += height + GAP_Y_PT
    width = max(b.x + b.w for b in placed.values())
    for layer in layers:  # centre each layer on the widest one
        row = [b for b in placed.values() if b.layer == layer]
        shift = (width - (max(b.x + b.w for b in row) - min(b.x for b in row))) / 2
        for b in row:
            placed[b.key] = Box(b.key, b.lines, b.kind, b.x + shift, b.y, b.w, b.h, b.layer)
    return placed


def _segments(graph: TaskGraph, placed: dict[str, Box]) -> list[tuple[Box, Box, str, bool]]:
    """(from box, to box, kind, back) for each edge: source -> its label -> target."""
    segs = []
    for e in graph.edges:
        label = placed[f"edge:{e.id}"]
        segs.append((placed[e.source], label, e.kind, False))
        segs.append((label, placed[e.target], e.kind, placed[e.target].y <= label.y))
    return segs


def write_graph_picture(graph: TaskGraph, path: str | Path, dpi: int = 120) -> Path:
    """Draw the graph to a PNG file (no display needed); returns the path written."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

    placed = boxes(graph)
    margin = 20.0
    width = max(b.x + b.w for b in placed.values()) + 2 * margin
    height = max(b.y + b.h for b in placed.values()) + 2 * margin + 16
    fig = Figure(figsize=(max(width, 360) / 72, height / 72))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(-margin, max(width, 360) - margin)
    ax.set_ylim(height - margin, -margin - 16)  # y grows downwards, as in the layout
    ax.set_axis_off()
    patches = {}
    for b in placed.values():
        colour = NOMINAL if b.kind == "nominal" else RECOVERY
        is_node = not b.key.startswith("edge:")
        thick = 2.4 if b.key in (graph.start, graph.goal) else 1.2
        patch = FancyBboxPatch((b.x, b.y), b.w, b.h, boxstyle="round,pad=0,rounding_size=3",
                               facecolor="white" if is_node else "#f7f7f7", edgecolor=colour,
                               linewidth=thick if is_node else 0.6, linestyle="-" if b.kind == "nominal" else "--")
        ax.add_patch(patch)
        patches[b.key] = patch
        for i, line in enumerate(b.lines):
            ax.text(b.x + PAD_PT, b.y + PAD_PT + (i + 0.8) * LINE_PT, line, fontsize=FONT_PT, family="monospace",
                    color="#222" if is_node and i == 0 else colour, va="baseline",
                    weight="bold" if is_node and i == 0 else "normal")
    for a, b, kind, back in _segments(graph, placed):
        colour = NOMINAL if kind == "nominal" else RECOVERY
        ax.add_patch(FancyArrowPatch(a.centre, b.centre, patchA=patches[a.key], patchB=patches[b.key],
                                     arrowstyle="-|>", mutation_scale=9, color=colour, linewidth=0.9,
                                     linestyle="-" if kind == "nominal" else "--", alpha=0.8,
                                     connectionstyle="arc3,rad=0.35" if back else "arc3,rad=0"))
    ax.legend(handles=[Line2D([], [], color=NOMINAL, label="nominal"),
                       Line2D([], [], color=RECOVERY, linestyle="--", label="recovery")],
              loc="upper right", fontsize=FONT_PT)
    ax.text(0, -margin / 2 - 4, graph.task or "task graph", fontsize=10, weight="bold", va="center")
    out = Path(path)
    fig.savefig(out, dpi=dpi)
    return out


def _details(graph: TaskGraph, key: str) -> str:
    """The hover text of a box: a node's constraints, or an edge's actions with their arguments and monitors."""
    if key.startswith("edge:"):
        e = next(x for x in graph.edges if x.id == key[5:])
        lines = [f"{e.id} ({e.kind}): {e.source} -> {e.target}, cost {e.cost:g}"]
        lines += [f"  {a.name}({', '.join(f'{k}={v}' for k, v in a.args.items())})" for a in e.actions]
        lines += [f"  monitor {m.id}: {m.failure_mode} -> {m.recovery or 'detect only'}" for m in e.monitors]
        return "\n".join(lines)
    n = next(x for x in graph.nodes if x.id == key)
    return "\n".join([f"{n.id} ({n.kind}): {n.description}", *(f"  {c}" for c in n.constraints)])


_PAGE = """<!doctype html><html><head><meta charset="utf-8"><title>{title}</title><style>
body{{margin:0;font-family:system-ui,sans-serif}}header{{padding:.5em 1em;background:#f3f3f3}}
svg{{width:100vw;height:calc(100vh - 3em);cursor:grab;display:block}}text{{font-size:{font}px;font-family:"DejaVu Sans Mono",monospace}}
g.box:hover rect{{stroke-width:3}}</style></head><body><header><b>{title}</b> &mdash; scroll to zoom, drag to
pan, hover a box for its details. <span style="color:{nom}">&#9632; nominal</span>
<span style="color:{rec}">&#9632; recovery</span></header>
<svg id="g" viewBox="{vb}" xmlns="http://www.w3.org/2000/svg"><defs>
<marker id="an" markerWidth="8" markerHeight="8" refX="7" refY="4" orient="auto"><path d="M0,0 L8,4 L0,8 z" fill="{nom}"/></marker>
<marker id="ar" markerWidth="8" markerHeight="8" refX="7" refY="4" orient="auto"><path d="M0,0 L8,4 L0,8 z" fill="{rec}"/></marker>
</defs>{body}</svg><script>
const s=document.getElementById('g');let v=s.getAttribute('viewBox').split(' ').map(Number),d=null;
const set=()=>s.setAttribute('viewBox',v.join(' '));
s.addEventListener('wheel',e=>{{e.preventDefault();const k=e.deltaY>0?1.15:1/1.15,r=s.getBoundingClientRect(),
px=v[0]+(e.clientX-r.left)/r.width*v[2],py=v[1]+(e.clientY-r.top)/r.height*v[3];
v=[px-(px-v[0])*k,py-(py-v[1])*k,v[2]*k,v[3]*k];set();}});
s.addEventListener('mousedown',e=>{{d=[e.clientX,e.clientY];}});window.addEventListener('mouseup',()=>{{d=null;}});
s.addEventListener('mousemove',e=>{{if(!d)return;const r=s.getBoundingClientRect();
v[0]-=(e.clientX-d[0])/r.width*v[2];v[1]-=(e.clientY-d[1])/r.height*v[3];d=[e.clientX,e.clientY];set();}});
</script></body></html>
"""


def graph_html(graph: TaskGraph) -> str:
    """A self-contained HTML page: the same layout as the PNG, as an SVG to zoom and pan, with hover details."""
    placed = boxes(graph)
    parts = []
    for a, b, kind, back in _segments(graph, placed):
        colour, mark = (NOMINAL, "an") if kind == "nominal" else (RECOVERY, "ar")
        (x0, y0), (x1, y1) = a.centre, b.centre
        y0, y1 = (a.y + a.h, b.y) if not back else (y0, y1)
        bend = f"Q{max(x0, x1) + 60:.1f},{(y0 + y1) / 2:.1f} " if back else ""
        dash = "" if kind == "nominal" else ' stroke-dasharray="5,3"'
        parts.append(f'<path d="M{x0:.1f},{y0:.1f} {bend}{x1:.1f},{y1:.1f}" fill="none" stroke="{colour}" '
                     f'stroke-width="1" opacity=".8" marker-end="url(#{mark})"{dash}/>')
    for b in placed.values():
        colour = NOMINAL if b.kind == "nominal" else RECOVERY
        is_node = not b.key.startswith("edge:")
        width = 2.5 if b.key in (graph.start, graph.goal) else 1.2 if is_node else 0.6
        dash = "" if b.kind == "nominal" else ' stroke-dasharray="4,2"'
        bold = ' font-weight="bold"'
        text = "".join(f'<text x="{b.x + PAD_PT:.1f}" y="{b.y + PAD_PT + (i + 0.8) * LINE_PT:.1f}" '
                       f'fill="{"#222" if is_node and i == 0 else colour}"{bold if is_node and i == 0 else ""}>'
                       f'{html.escape(line)}</text>' for i, line in enumerate(b.lines))
        parts.append(f'<g class="box"><title>{html.escape(_details(graph, b.key))}</title>'
                     f'<rect x="{b.x:.1f}" y="{b.y:.1f}" width="{b.w:.1f}" height="{b.h:.1f}" rx="3" '
                     f'fill="{"white" if is_node else "#f7f7f7"}" stroke="{colour}" stroke-width="{width}"{dash}/>'
                     f'{text}</g>')
    w = max(b.x + b.w for b in placed.values()) + 40
    h = max(b.y + b.h for b in placed.values()) + 40
    return _PAGE.format(title=html.escape(graph.task or "task graph"), font=FONT_PT, nom=NOMINAL, rec=RECOVERY,
                        vb=f"-20 -20 {w:.0f} {h:.0f}", body="".join(parts))


def write_graph_html(graph: TaskGraph, path: str | Path) -> Path:
    out = Path(path)
    out.write_text(graph_html(graph))
    return out
