"""Graph pictures: DOT text with nominal/recovery styles, and a real PNG drawn headless."""

from __future__ import annotations

import re

import numpy as np
from matplotlib.image import imread

from kintsugi.taskgraph import to_dot, write_graph_picture
from kintsugi.taskgraph.forward import forward_filter
from kintsugi.taskgraph.model import TaskGraph
from kintsugi.taskgraph.render import NOMINAL, RECOVERY, boxes
from tests.taskgraph_fixtures import pour_graph, pour_graph_data


def test_dot_styles_and_escaping():
    data = pour_graph_data()
    data["task"] = 'pour "water"\\ now'
    data["nodes"][0]["description"] = 'say "hi"\nthen go'
    dot = to_dot(TaskGraph.from_data(data))
    assert dot.startswith('digraph "pour \\"water\\"\\\\ now" {')
    assert '"home" -> "grasped"' in dot and 'label="home\\nsay \\"hi\\"\\nthen go"' in dot
    edges = [line for line in dot.splitlines() if "->" in line]
    assert len(edges) == len(data["edges"])
    for line in edges:
        rec = re.search(r'"(r_\w+): ', line) is not None
        assert ("style=dashed" in line) == rec and (RECOVERY in line) == rec and (NOMINAL in line) != rec
    assert dot.count("peripheries=2") == 2  # start and goal
    assert "m_drop: drop -> r_pick" in dot and "m_vis: tracking_lost -> detect only" in dot


def test_layout_layers_nominal_top_down_with_recovery_beside_and_no_overlaps():
    placed = boxes(pour_graph())
    ys = [placed[n].y for n in ("home", "grasped", "over_cup", "poured", "done")]
    assert ys == sorted(ys) and len(set(ys)) == 5
    assert placed["regrasp"].y > placed["grasped"].y and placed["regrasp"].kind == "recovery"
    items = list(placed.values())
    assert not [(a.key, b.key) for i, a in enumerate(items) for b in items[i + 1:] if a.overlaps(b)]


def test_picture_is_written(tmp_path):
    for name, graph in (("full", pour_graph()), ("filtered", forward_filter(pour_graph()).graph)):
        out = write_graph_picture(graph, tmp_path / f"{name}.png")
        img = imread(out)
        assert img.shape[0] > 200 and img.shape[1] > 400
        rgb = img[..., :3]
        # Both colours are actually drawn (nominal blue and recovery pink pixels).
        for hexcol in (NOMINAL, RECOVERY):
            c = np.array([int(hexcol[i:i + 2], 16) / 255 for i in (1, 3, 5)])
            assert (np.abs(rgb - c).max(axis=-1) < 0.08).sum() > 50, (name, hexcol)
