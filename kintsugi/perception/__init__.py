"""Perception: camera images to measurements (peg/hole segmentation, tilt, Table I checks)."""

from kintsugi.perception.checks import align_check, compression_check, fit_check, pose_check
from kintsugi.perception.compare import compare_to_goal
from kintsugi.perception.segment import PerceptionConfig, SceneMeasurement, measure, peg_mask

__all__ = [
    "PerceptionConfig",
    "SceneMeasurement",
    "align_check",
    "compare_to_goal",
    "compression_check",
    "fit_check",
    "measure",
    "peg_mask",
    "pose_check",
]
