"""Named peg-insertion campaigns: a harder world and the options a run uses, fixed by name.

`stretch` is the world where the paper's method still breaks (large in-grasp angles with a
tight hole, the hole far off, sticky walls) with the options beyond the paper on:
re-approach in recovery plans and the side camera. `stretch-paper` is the same world with
the options off, so the paper-faithful method's figures sit beside it. A user's `--set`
overrides apply on top of a suite's.

The hole's x offset stays off: the arm moves only in y, z and roll (the paper's planar
task), and with 1 mm clearance the wrist's compliance absorbs at most ~0.6 mm of x offset
for a flat-sided peg (measured: straight-down inserts succeed at 0.6 mm, fail at 1 mm), so
an offset of a few millimetres would make most trials infeasible for any method.
"""

from __future__ import annotations

from typing import Any

from kintsugi.core.suite import Suite
from kintsugi.core.config import apply_overrides
from kintsugi.core.resolve import split_overrides
from kintsugi.core.errors import UnknownNameError
from kintsugi.worlds.peg.config import RECOVERY_SKILL_NAMES, PegTaskConfig


class PegSuite(Suite):
    """A peg-insertion suite; `config()` is its world, for checks of the suite itself."""

    def config(self) -> PegTaskConfig:
        return apply_overrides(PegTaskConfig(), split_overrides(self.overrides)[0])

    def method_overrides(self, method: str) -> dict[str, Any]:
        """The suite's settings of one method (`methods.<method>.<key>`), without the prefix."""
        return split_overrides(self.overrides, method)[1]


STRETCH_WORLD: dict[str, Any] = {
    "grasp.angle_deg": [-10.0, 10.0],
    "hole.y_offset_mm": [-30.0, 30.0],
    "hole.friction_scale": [1.0, 10.0],
    "peg.clearance_mm": 1.0,
}
OPTIONS_ON: dict[str, Any] = {"methods.recovery.skills": list(RECOVERY_SKILL_NAMES), "camera.side_view": True}
OPTIONS_OFF: dict[str, Any] = {"methods.recovery.skills": ["fit", "align", "insert"], "camera.side_view": False}
_CELLS = dict(shapes=("round", "square", "rectangle"), conditions=("all",), trials=30)

SUITES: dict[str, PegSuite] = {
    s.name: s
    for s in (
        PegSuite(
            name="stretch",
            description="grasp +-10 deg, hole +-30 mm, friction x1-10, clearance 1 mm; "
                        "recovery may re-approach and sees a side camera",
            methods=("baseline", "recovery"), overrides=STRETCH_WORLD | OPTIONS_ON, companion="stretch-paper",
            **_CELLS,
        ),
        PegSuite(
            name="stretch-paper",
            description="the stretch world with the paper's method as published (CF2..CF4 plans, one camera)",
            methods=("recovery",), overrides=STRETCH_WORLD | OPTIONS_OFF, companion="stretch",
            **_CELLS,
        ),
    )
}


def suite(name: str) -> PegSuite:
    try:
        return SUITES[name]
    except KeyError:
        raise UnknownNameError(f"unknown suite {name!r}; known: {', '.join(SUITES)}") from None


def suite_overrides(name: str) -> dict[str, Any]:
    """The config overrides of a named suite (a copy; `--set` values go on top)."""
    return dict(suite(name).overrides)
