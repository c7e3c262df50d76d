"""Peg and hole segmentation by HSV thresholds, and their measurements in pixels and mm.

Pixel convention: pixel (i, j) covers [i, i + 1) x [j, j + 1), so a bounding
box (x, y, w, h) spans [x, x + w] horizontally and its centre is x + w / 2.
This matches MuJoCo's renderer with ``cu = width / 2`` (the optical axis
falls on the boundary between the two middle columns).
Millimetres come from ``CameraCalibration.to_plane``: y grows to the right
(u), z grows upward (against v).

The colour thresholds and check tolerances (`PerceptionConfig`) are defined in
`kintsugi.perception.types`, with the other observation types.
"""

from __future__ import annotations

import cv2
import numpy as np
from pydantic import Field

from kintsugi.core.config import StrictModel
from kintsugi.perception.tilt import TiltMethod, estimate_tilt
from kintsugi.perception.types import CameraCalibration, HsvRange, PerceptionConfig  # noqa: F401 - re-exported


class Blob(StrictModel):
    """One segmented region. Pixel boxes are (x, y, w, h); *_mm edges are y (left/right) or z (top/bottom)."""

    bbox_px: tuple[int, int, int, int]
    area_px: float
    center_px: tuple[float, float]
    center_mm: tuple[float, float] = Field(description="(y, z) of the bounding-box centre")
    left_mm: float
    right_mm: float
    top_mm: float
    bottom_mm: float


class PegBlob(Blob):
    """The peg's visible part: P_center is ``center_mm``, P_edge is ``edge_mm`` (bottom-right)."""

    edge_px: tuple[float, float]
    edge_mm: tuple[float, float]
    tilt_deg: float = Field(description="peg axis from vertical, + when the top leans left, in (-90, 90]")
    tilt_method: TiltMethod


class SceneMeasurement(StrictModel):
    """What the camera shows; ``peg`` or ``hole`` is None when not found (never an exception)."""

    image_size: tuple[int, int]
    peg: PegBlob | None
    hole: Blob | None


def _mask(hsv: np.ndarray, ranges: list[HsvRange], cfg: PerceptionConfig) -> np.ndarray:
    mask = np.zeros(hsv.shape[:2], np.uint8)
    for r in ranges:
        mask |= cv2.inRange(hsv, np.array(r.lower, np.uint8), np.array(r.upper, np.uint8))
    if cfg.open_kernel_px > 1:
        k = cv2.getStructuringElement(cv2.MORPH_RECT, (cfg.open_kernel_px, cfg.open_kernel_px))
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, k)
    if cfg.close_kernel_px > 1:  # fills specular highlights inside the peg
        k = cv2.getStructuringElement(cv2.MORPH_RECT, (cfg.close_kernel_px, cfg.close_kernel_px))
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, k)
    return mask


def _to_hsv(image_rgb: np.ndarray) -> np.ndarray:
    img = np.asarray(image_rgb)
    if img.ndim != 3 or img.shape[2] < 3:
        raise ValueError(f"expected an RGB image of shape (H, W, 3), got {img.shape}")
    return cv2.cvtColor(np.ascontiguousarray(img[:, :, :3], dtype=np.uint8), cv2.COLOR_RGB2HSV)


def _largest(mask: np.ndarray, min_area: float) -> np.ndarray | None:
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    best = max(contours, key=cv2.contourArea, default=None)
    if best is None or cv2.contourArea(best) < min_area or len(best) < 3:
        return None
    return best


def peg_mask(image_rgb: np.ndarray, cfg: PerceptionConfig) -> np.ndarray:
    """Binary mask (0/255) of the largest peg-coloured region; all zero if none."""
    mask = _mask(_to_hsv(image_rgb), cfg.peg_hsv, cfg)
    out = np.zeros_like(mask)
    contour = _largest(mask, cfg.min_area_px)
    if contour is not None:
        cv2.drawContours(out, [contour], -1, 255, thickness=cv2.FILLED)
        out &= mask
    return out


def _blob_fields(contour: np.ndarray, calib: CameraCalibration, area: float | None = None) -> dict:
    x, y, w, h = cv2.boundingRect(contour)
    cu, cv_ = x + w / 2.0, y + h / 2.0
    left, top = calib.to_plane(x, y)
    right, bottom = calib.to_plane(x + w, y + h)
    return dict(
        bbox_px=(x, y, w, h),
        area_px=float(cv2.contourArea(contour)) if area is None else area,
        center_px=(cu, cv_),
        center_mm=calib.to_plane(cu, cv_),
        left_mm=left,
        right_mm=right,
        top_mm=top,
        bottom_mm=bottom,
    )


def _peg(contour: np.ndarray, calib: CameraCalibration, size: tuple[int, int]) -> PegBlob:
    fields = _blob_fields(contour, calib)
    x, y, w, h = fields["bbox_px"]
    edge_px = (float(x + w), float(y + h))
    tilt, method = estimate_tilt(contour, size)
    return PegBlob(**fields, edge_px=edge_px, edge_mm=calib.to_plane(*edge_px), tilt_deg=tilt, tilt_method=method)


def measure(image_rgb: np.ndarray, calib: CameraCalibration, cfg: PerceptionConfig | None = None) -> SceneMeasurement:
    """Segment peg (largest cyan contour) and hole (largest red contour) and measure them.

    The hole is the largest red contour, as in the paper; if something in
    front splits the red face, red pieces sharing its rows and no farther
    away than its own width are merged, so H_center stays the face's centre.
    """
    cfg = cfg or PerceptionConfig()
    hsv = _to_hsv(image_rgb)
    size = (hsv.shape[1], hsv.shape[0])
    peg_c = _largest(_mask(hsv, cfg.peg_hsv, cfg), cfg.min_area_px)
    hole = _hole_contour(_mask(hsv, cfg.hole_hsv, cfg), cfg.min_area_px)
    return SceneMeasurement(
        image_size=size,
        peg=None if peg_c is None else _peg(peg_c, calib, size),
        hole=None if hole is None else Blob(**_blob_fields(hole[0], calib, hole[1])),
    )


def _hole_contour(mask: np.ndarray, min_area: float) -> tuple[np.ndarray, float] | None:
    """(points of the hole's face, its area in px), or None."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    areas = [cv2.contourArea(c) for c in contours]
    if not contours or max(areas) < min_area:
        return None
    i_best = int(np.argmax(areas))
    bx, by, bw, bh = cv2.boundingRect(contours[i_best])
    parts = [i_best]
    for i, c in enumerate(contours):
        if i == i_best or areas[i] < 4:
            continue
        x, y, w, h = cv2.boundingRect(c)
        overlaps_rows = y <= by + bh and by <= y + h
        gap = max(x - (bx + bw), bx - (x + w))  # horizontal gap, negative when overlapping
        near_cols = gap <= bw
        if overlaps_rows and near_cols:
            parts.append(i)
    points = np.concatenate([contours[i] for i in parts])
    return points, float(sum(areas[i] for i in parts))


def board_surface_v(image_rgb: np.ndarray, min_fraction: float = 0.5) -> float | None:
    """Image v of the board's top surface (the top boundary of the first mostly-grey row).

    Grey = low saturation and mid brightness; returns None when no such row exists.
    """
    hsv = _to_hsv(image_rgb)
    grey = (hsv[:, :, 1] < 40) & (hsv[:, :, 2] > 60) & (hsv[:, :, 2] < 235)
    frac = grey.mean(axis=1)
    rows = np.flatnonzero(frac >= min_fraction)
    # Require the row below to be grey too, so a stray grey line does not count.
    for r in rows:
        if r + 1 < len(frac) and frac[r + 1] >= min_fraction:
            return float(r)
    return None
