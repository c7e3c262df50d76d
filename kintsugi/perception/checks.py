"""Mechanical success checks of the paper (Sec. V-A): Table I vision rules, pose error, compression limit.

Each returns a ``CheckResult`` whose message is Table I's wording verbatim
(the reasoner and its prompts key on them) and whose measurements are in mm
and degrees. Tilt is + when the top of the peg leans left in the image.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from kintsugi.perception.segment import PerceptionConfig, SceneMeasurement
from kintsugi.perception.types import Axis, CheckResult, Pose

FIT_SUCCESS = "success"
FIT_GY_TOO_SMALL = "p_gy was too small."
FIT_GY_TOO_BIG = "p_gy was too big."

ALIGN_SUCCESS = "Align success"
ALIGN_ON_TILTED_LEFT = "peg is tilted to the left."
ALIGN_ON_TILTED_RIGHT = "peg is tilted to the right."
ALIGN_LEFT = "p_ey was too small."
ALIGN_RIGHT = "p_ey was too big."
ALIGN_LEFT_TILTED_LEFT = "peg is tilted to the left. p_gy was too small."
ALIGN_RIGHT_TILTED_LEFT = "p_gy was too big. also tilted to the left."
ALIGN_LEFT_TILTED_RIGHT = "p_gy was too small. also tilted to the right."
ALIGN_RIGHT_TILTED_RIGHT = "p_gy was too big. also tilted to the right."

# (relative position, tilt class) -> message; positions: left/on/right of the hole, tilts: left/within/right.
ALIGN_TABLE: dict[tuple[str, str], str] = {
    ("on", "within"): ALIGN_SUCCESS,
    ("on", "left"): ALIGN_ON_TILTED_LEFT,
    ("on", "right"): ALIGN_ON_TILTED_RIGHT,
    ("left", "within"): ALIGN_LEFT,
    ("right", "within"): ALIGN_RIGHT,
    ("left", "left"): ALIGN_LEFT_TILTED_LEFT,
    ("right", "left"): ALIGN_RIGHT_TILTED_LEFT,
    ("left", "right"): ALIGN_LEFT_TILTED_RIGHT,
    ("right", "right"): ALIGN_RIGHT_TILTED_RIGHT,
}


def _missing(name: str, scene: SceneMeasurement) -> CheckResult | None:
    """A failed result naming what the camera could not find, or None if both are visible."""
    gone = [what for what, blob in (("peg", scene.peg), ("hole", scene.hole)) if blob is None]
    if not gone:
        return None
    what = " and ".join(gone)
    return CheckResult(
        name=name,
        passed=False,
        message=f"{what} not visible in the image (no {'/'.join(gone)}-coloured region large enough).",
        measurements={"peg_visible": float(scene.peg is not None), "hole_visible": float(scene.hole is not None)},
    )


def _common(scene: SceneMeasurement) -> dict[str, float]:
    peg, hole = scene.peg, scene.hole
    assert peg is not None and hole is not None
    return {
        "peg_center_y_mm": peg.center_mm[0],
        "peg_center_z_mm": peg.center_mm[1],
        "peg_edge_y_mm": peg.edge_mm[0],
        "peg_top_z_mm": peg.top_mm,
        "peg_bottom_z_mm": peg.bottom_mm,
        "hole_center_y_mm": hole.center_mm[0],
        "offset_y_mm": peg.center_mm[0] - hole.center_mm[0],
        "tilt_deg": peg.tilt_deg,
    }


def fit_check(scene: SceneMeasurement) -> CheckResult:
    """Table I, Fit: the peg's centre is at/left of the hole centre and its right edge past it."""
    if (missing := _missing("vision_fit", scene)) is not None:
        return missing
    m = _common(scene)
    p_center, p_edge, h_center = m["peg_center_y_mm"], m["peg_edge_y_mm"], m["hole_center_y_mm"]
    if p_center <= h_center and p_edge > h_center:
        message = FIT_SUCCESS
    elif p_center <= h_center:
        message = FIT_GY_TOO_SMALL
    else:
        message = FIT_GY_TOO_BIG
    return CheckResult(name="vision_fit", passed=message == FIT_SUCCESS, message=message, measurements=m)


def align_class(offset_mm: float, tilt_deg: float, cfg: PerceptionConfig) -> tuple[str, str]:
    """(left/on/right of the hole, left/within/right tilt) with the config's tolerances."""
    pos = "on" if abs(offset_mm) <= cfg.align_tol_mm else ("left" if offset_mm < 0 else "right")
    tilt = "within" if abs(tilt_deg) <= cfg.tilt_tol_deg else ("left" if tilt_deg > 0 else "right")
    return pos, tilt


def align_check(scene: SceneMeasurement, cfg: PerceptionConfig | None = None) -> CheckResult:
    """Table I, Align: peg centre over the hole centre and peg upright within tolerance."""
    cfg = cfg or PerceptionConfig()
    if (missing := _missing("vision_align", scene)) is not None:
        return missing
    m = _common(scene)
    m |= {"align_tol_mm": cfg.align_tol_mm, "tilt_tol_deg": cfg.tilt_tol_deg}
    message = ALIGN_TABLE[align_class(m["offset_y_mm"], m["tilt_deg"], cfg)]
    return CheckResult(name="vision_align", passed=message == ALIGN_SUCCESS, message=message, measurements=m)


def pose_check(
    goal: Pose, terminal: Pose, axes: Sequence[Axis], threshold_mm: float = 1.0, threshold_deg: float = 1.0
) -> CheckResult:
    """‖p_g − p_e‖ over the skill's own axes (paper: 1 mm).

    Millimetres and degrees do not add, so y/z form the norm compared with
    ``threshold_mm`` and roll, if it is one of the axes, is held to ``threshold_deg``.
    """
    errs = {a: getattr(terminal, a) - getattr(goal, a) for a in axes}
    lin = math.hypot(*(errs[a] for a in ("y", "z") if a in errs))
    roll = abs(errs.get("roll", 0.0))
    passed = lin <= threshold_mm and roll <= threshold_deg
    m = {f"error_{a}_{'deg' if a == 'roll' else 'mm'}": e for a, e in errs.items()}
    m |= {"error_norm_mm": lin, "threshold_mm": threshold_mm}
    axes_txt = ", ".join(axes) or "none"
    if passed:
        message = f"goal pose reached on axes [{axes_txt}]: error {lin:.2f} mm (threshold {threshold_mm:g} mm)."
    else:
        parts = [f"{a} off by {e:+.2f} {'deg' if a == 'roll' else 'mm'}" for a, e in errs.items()]
        message = f"goal pose not reached on axes [{axes_txt}]: " + ", ".join(parts) + f" (error {lin:.2f} mm)."
    if "roll" in errs:
        m["threshold_deg"] = threshold_deg
    return CheckResult(name="pose", passed=passed, message=message, measurements=m)


def compression_check(limit_hit: bool, force_n: float) -> CheckResult:
    """Whether the soft wrist's z-compression limit halted the skill."""
    if limit_hit:
        message = f"compression limit reached (wrist z force {force_n:.1f} N); the skill was halted."
    else:
        message = f"compression limit not reached (wrist z force {force_n:.1f} N)."
    return CheckResult(
        name="compression",
        passed=not limit_hit,
        message=message,
        measurements={"force_z_n": force_n, "limit_hit": float(limit_hit)},
    )
