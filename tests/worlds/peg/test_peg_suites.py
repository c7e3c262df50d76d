"""Named suites: each is a valid peg config, `stretch` and `stretch-paper` share one world and
differ only in the options, and an unknown name lists the known ones."""

from __future__ import annotations

import pytest

from kintsugi.core.resolve import split_overrides
from kintsugi.methods.recovery.settings import RecoverySettings

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import KintsugiError
from kintsugi.worlds.peg.conditions import sample_params
from kintsugi.worlds.peg.config import CONDITIONS, PegTaskConfig
from kintsugi.worlds.peg.shapes import peg_shape
from kintsugi.worlds.peg.suites import SUITES, suite, suite_overrides


@pytest.mark.parametrize("name", list(SUITES))
def test_every_suite_is_a_valid_campaign(name: str) -> None:
    s = suite(name)
    cfg = s.config()
    assert set(s.conditions) <= set(CONDITIONS)
    for shape in s.shapes:
        peg_shape(shape, cfg)
    assert s.companion is None or s.companion in SUITES
    assert suite_overrides(name) == s.overrides and suite_overrides(name) is not s.overrides


def test_stretch_world_and_options() -> None:
    on, off = suite("stretch").config(), suite("stretch-paper").config()
    assert on.grasp.angle_deg == (-10.0, 10.0) and on.hole.y_offset_mm == (-30.0, 30.0)
    assert on.hole.friction_scale == (1.0, 10.0) and on.peg.clearance_mm == 1.0
    assert on.hole.x_offset_mm == (0.0, 0.0)  # infeasible for a planar arm beyond ~0.6 mm (see suites.py)
    on_rec = RecoverySettings(**suite("stretch").method_overrides("recovery"))
    off_rec = RecoverySettings(**suite("stretch-paper").method_overrides("recovery"))
    assert on_rec.skills == ("approach", "contact", "fit", "align", "insert") and on.camera.side_view
    assert off_rec.skills == RecoverySettings().skills and not off.camera.side_view
    # Same world: every trial draws the same truth in both suites.
    assert on.model_dump(exclude={"camera"}) == off.model_dump(exclude={"camera"})
    for seed in range(3):
        assert sample_params(on, "round", "all", seed) == sample_params(off, "round", "all", seed)


def test_user_overrides_go_on_top() -> None:
    task, method, _ = split_overrides(suite_overrides("stretch") | {"peg.clearance_mm": 0.5}, "recovery")
    cfg = apply_overrides(PegTaskConfig(), task)
    assert cfg.peg.clearance_mm == 0.5 and cfg.camera.side_view and "approach" in method["skills"]


def test_unknown_suite_lists_the_known_ones() -> None:
    with pytest.raises(KintsugiError) as exc:
        suite_overrides("strech")
    assert "'strech'" in str(exc.value) and "stretch, stretch-paper" in str(exc.value)
