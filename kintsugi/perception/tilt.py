"""Peg tilt from a contour, independent of OpenCV's minAreaRect angle convention.

Convention: signed tilt of the peg's axis from image vertical, in degrees in
(-90, 90], positive when the top of the peg leans to the left (counter-clockwise
as seen in the image). Image v grows downward.

Two estimates are made:

* ``min_area_rect`` (the paper's method): the long side of ``cv2.minAreaRect``.
  The angle is read from ``cv2.boxPoints`` edge vectors, never from the
  returned angle, because that angle's range changed in OpenCV 4.5.1
  ([-90, 0) before, (0, 90] after).
* ``hull_edges``: when the peg is mostly inside the hole its visible part is
  the peg rectangle cut by the horizontal board line; it can be wider than
  tall, and minAreaRect may then lock onto the horizontal cut and report 0°
  (or 90°). Every edge of the convex hull of a (clipped) rectangle is either
  parallel or perpendicular to the peg axis, except the cut itself and any
  image-border cut, so the length-weighted mean of hull-edge directions
  (each refined by ``cv2.fitLine`` on the contour pixels along it) folded
  modulo 90° gives the tilt in (-45, 45]. The peg never tilts 45° in this
  task, so the fold is harmless there.

``estimate_tilt`` uses minAreaRect's long side as the axis when the visible
part is clearly elongated, both estimates agree modulo 90°, and it is not a
board-cut stub whose long side is near horizontal (the value then comes from
the finer edge fit, on the branch the rect picks); otherwise it uses the hull
edges alone. So the full (-90, 90] range is kept for a wholly visible peg, and
a stub reads within ±45°. Known ambiguity: a peg lying flat (±90°) across the
board line looks exactly like an upright stub and reads as ~0°.
"""

from __future__ import annotations

import math
from typing import Literal

import cv2
import numpy as np

TiltMethod = Literal["min_area_rect", "hull_edges"]


def _axis_tilt(du: float, dv: float) -> float:
    """Tilt in (-90, 90] of a direction vector taken as the peg axis."""
    if dv > 0 or (dv == 0 and du > 0):
        du, dv = -du, -dv  # point the axis upward (v decreasing)
    t = math.degrees(math.atan2(-du, -dv))
    return 90.0 if t <= -90.0 else t


def fold90(angle_deg: float) -> float:
    """Fold an angle modulo 90° into (-45, 45]."""
    a = (angle_deg + 45.0) % 90.0 - 45.0
    return 45.0 if a == -45.0 else a


def rect_tilt(contour: np.ndarray) -> tuple[float, float]:
    """(tilt of the minAreaRect long side, long/short aspect ratio)."""
    box = cv2.boxPoints(cv2.minAreaRect(contour))
    e1, e2 = box[1] - box[0], box[2] - box[1]
    l1, l2 = float(np.hypot(*e1)), float(np.hypot(*e2))
    long_edge = e1 if l1 >= l2 else e2
    aspect = max(l1, l2) / max(min(l1, l2), 1e-9)
    return _axis_tilt(float(long_edge[0]), float(long_edge[1])), aspect


def _edge_direction(pts: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Axis-tilt reading of hull edge a->b, refined by a line fit to the contour points along it.

    Hull vertices sit on pixel corners, so the chord alone is off by up to
    1/length rad; fitting all boundary pixels of the middle of the edge is not.
    """
    d = b - a
    length = float(np.hypot(*d))
    unit = d / length
    rel = pts - a
    along = rel @ unit
    across = np.abs(rel[:, 0] * unit[1] - rel[:, 1] * unit[0])
    near = pts[(across <= 1.5) & (along >= 0.15 * length) & (along <= 0.85 * length)]
    if len(near) >= 5:
        vx, vy, _, _ = cv2.fitLine(near.astype(np.float32), cv2.DIST_L2, 0, 0.01, 0.01).ravel()
        return _axis_tilt(float(vx), float(vy))
    return _axis_tilt(float(d[0]), float(d[1]))


def hull_edge_tilt(contour: np.ndarray, image_size: tuple[int, int]) -> tuple[float | None, bool]:
    """(tilt folded into (-45, 45] from the hull's edges, whether a bottom cut was seen).

    A cut is a near-horizontal hull edge on the contour's lowest row (the
    board surface hides the rest of the peg) or any edge lying on the image
    border; cuts do not vote. The tilt is None if no usable edge is left.
    """
    width, height = image_size
    hull = cv2.convexHull(contour)
    hull = cv2.approxPolyDP(hull, 1.0, True).reshape(-1, 2).astype(float)
    if len(hull) < 3:
        return None, False
    v_max = hull[:, 1].max()
    span_u = hull[:, 0].max() - hull[:, 0].min()
    pts = contour.reshape(-1, 2).astype(float)
    edges = []
    cut = False
    for a, b in zip(hull, np.roll(hull, -1, axis=0)):
        du, dv = b - a
        length = math.hypot(du, dv)
        if length < 2.0:
            continue
        horizontal = abs(dv) <= max(1.0, 0.02 * length)
        if horizontal and min(a[1], b[1]) >= v_max - 1.5:
            # The board surface hides the rest of the peg (short flats are just digitised corners).
            cut = cut or length >= 0.3 * span_u
            continue
        on_border = (
            (a[0] <= 0.5 and b[0] <= 0.5)
            or (a[1] <= 0.5 and b[1] <= 0.5)
            or (a[0] >= width - 1.5 and b[0] >= width - 1.5)
            or (a[1] >= height - 1.5 and b[1] >= height - 1.5)
        )
        if on_border:
            continue
        edges.append((fold90(_edge_direction(pts, a, b)), length))
    if not edges:
        return None, cut
    longest = max(length for _, length in edges)
    # Corners of a digitised rectangle give short, wrongly angled hull edges; drop them.
    kept = [(a, w) for a, w in edges if w >= 0.25 * longest]
    # Mean on the circle of period 90° (angle * 4), weighted by edge length.
    s = sum(w * math.sin(math.radians(4 * a)) for a, w in kept)
    c = sum(w * math.cos(math.radians(4 * a)) for a, w in kept)
    return fold90(math.degrees(math.atan2(s, c)) / 4.0), cut


def estimate_tilt(
    contour: np.ndarray, image_size: tuple[int, int], min_aspect: float = 1.25, agree_deg: float = 3.0
) -> tuple[float, TiltMethod]:
    """Signed peg tilt (degrees, + = top leans left) and which estimate was used."""
    t_rect, aspect = rect_tilt(contour)
    t_edge, cut = hull_edge_tilt(contour, image_size)
    if t_edge is None:
        return t_rect, "min_area_rect"
    # A cut stub lying on its side (long side near horizontal) is wider than tall:
    # its long side is the peg's top edge, not its axis.
    stub = cut and abs(t_rect) > 45.0
    if aspect >= min_aspect and not stub and abs(fold90(t_rect - t_edge)) <= agree_deg:
        # The rect's long side says which of t_edge, t_edge ± 90 is the axis;
        # the edge fit gives the value (pixel-level minAreaRect is coarser).
        t = t_edge + 90.0 * round((t_rect - t_edge) / 90.0)
        return (t - 180.0 if t > 90.0 else t + 180.0 if t <= -90.0 else t), "min_area_rect"
    return t_edge, "hull_edges"
