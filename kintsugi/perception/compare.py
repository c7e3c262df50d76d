"""Insertion check support: compare the terminal image with the goal (peg inserted) image.

Once inside the hole the peg is hidden behind the board, so OpenCV cannot see
the insertion depth; the paper gives a goal image to the VLM instead. This
module turns that comparison into numbers (peg-top height above the board in
both images, peg-mask overlap, horizontal offset) for the reasoner to fuse
with the pose and compression checks. Its ``passed`` is a measurement-level
opinion, not the verdict.

"Peg top" is the top of the peg's *visible* cyan region: the gripper's
fingers or the frame edge may hide the real top, but they do so the same way
in the goal image, so the difference is still how much deeper the peg must go.
"""

from __future__ import annotations

import numpy as np

from kintsugi.perception.segment import PerceptionConfig, board_surface_v, measure, peg_mask
from kintsugi.perception.types import CameraCalibration, CheckResult


def surface_z_mm(image_rgb: np.ndarray, calib: CameraCalibration, cfg: PerceptionConfig) -> float:
    """Board surface z from the image (first mostly-grey row), else the configured value."""
    v = board_surface_v(image_rgb)
    return cfg.board_surface_z_mm if v is None else calib.to_plane(0.0, v)[1]


def mask_iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two masks; two empty masks agree (1.0)."""
    a, b = a > 0, b > 0
    union = np.count_nonzero(a | b)
    return 1.0 if union == 0 else np.count_nonzero(a & b) / union


def compare_to_goal(
    terminal_rgb: np.ndarray, goal_rgb: np.ndarray, calib: CameraCalibration, cfg: PerceptionConfig | None = None
) -> CheckResult:
    """Does the terminal image show the peg as far down as the goal image does?

    Passed when the terminal peg top is within ``insert_top_tol_mm`` of the
    goal's and, if the goal shows the peg, the terminal shows it in the same
    place (mask IoU >= ``insert_min_iou``). A peg hidden entirely counts as
    its top at the board surface (height 0).
    """
    cfg = cfg or PerceptionConfig()
    term, goal = measure(terminal_rgb, calib, cfg), measure(goal_rgb, calib, cfg)
    iou = mask_iou(peg_mask(terminal_rgb, cfg), peg_mask(goal_rgb, cfg))
    h_term = 0.0 if term.peg is None else term.peg.top_mm - surface_z_mm(terminal_rgb, calib, cfg)
    h_goal = 0.0 if goal.peg is None else goal.peg.top_mm - surface_z_mm(goal_rgb, calib, cfg)
    diff = h_term - h_goal
    m = {
        "peg_top_above_surface_mm": h_term,
        "goal_peg_top_above_surface_mm": h_goal,
        "top_difference_mm": diff,
        "peg_mask_iou": iou,
        "peg_visible": float(term.peg is not None),
        "goal_peg_visible": float(goal.peg is not None),
    }
    if term.peg is not None and goal.peg is not None:
        m["offset_y_mm"] = term.peg.center_mm[0] - goal.peg.center_mm[0]
    height_ok = abs(diff) <= cfg.insert_top_tol_mm
    place_ok = goal.peg is None or (term.peg is not None and iou >= cfg.insert_min_iou)
    passed = height_ok and place_ok

    parts = []
    if term.peg is None:
        parts.append("peg not visible (hidden below the board surface or out of view)")
    else:
        parts.append(f"visible peg top {h_term:.1f} mm above the board surface")
    parts.append("goal image: peg not visible" if goal.peg is None else f"goal image: {h_goal:.1f} mm")
    parts.append(f"difference {diff:+.1f} mm (tolerance {cfg.insert_top_tol_mm:g} mm)")
    parts.append(f"peg-mask IoU with goal {iou:.2f}")
    if "offset_y_mm" in m:
        parts.append(f"horizontal offset from goal {m['offset_y_mm']:+.1f} mm")
    verdict = "matches the goal image" if passed else "does not match the goal image"
    return CheckResult(name="insert_image", passed=passed, message="; ".join(parts) + f" -> {verdict}.", measurements=m)
