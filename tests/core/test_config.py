"""`--set key=value` overrides on the peg task config: they apply, and every mistake is a
ConfigError that names the key (and, for unknown keys, lists the keys that exist)."""

from __future__ import annotations

import pytest

from kintsugi.core.config import apply_overrides, parse_override
from kintsugi.core.errors import ConfigError, KintsugiError
from kintsugi.worlds.peg.conditions import sample_params
from kintsugi.worlds.peg.config import PegTaskConfig

BASE = PegTaskConfig()


def test_documented_overrides_apply() -> None:
    cfg = apply_overrides(BASE, ["hole.friction_scale=[1,5]", "peg.clearance_mm=2", "grasp.angle_deg=[-5,5]"])
    assert cfg.hole.friction_scale == (1.0, 5.0)
    assert cfg.peg.clearance_mm == 2.0
    assert cfg.grasp.angle_deg == (-5.0, 5.0)


def test_overrides_change_values_and_leave_the_original_alone() -> None:
    cfg = apply_overrides(BASE, ["hole.friction_scale=[2, 3.5]", "peg.clearance_mm=0.5",
                                 "grasp.angle_deg=[-1,1]", "wrist.z_stiffness=2500", "camera.width=640"])
    assert cfg.hole.friction_scale == (2.0, 3.5)
    assert cfg.peg.clearance_mm == 0.5
    assert cfg.grasp.angle_deg == (-1.0, 1.0)
    assert cfg.wrist.z_stiffness == 2500.0
    assert cfg.camera.width == 640
    assert BASE.peg.clearance_mm == 2.0 and BASE.hole.friction_scale == (1.0, 5.0)
    assert cfg.hole.depth_mm == BASE.hole.depth_mm  # untouched keys keep their defaults


def test_dict_overrides_match_text_overrides() -> None:
    from_text = apply_overrides(BASE, ["hole.friction_scale=[1,2]", "peg.clearance_mm=3"])
    from_dict = apply_overrides(BASE, {"hole.friction_scale": [1, 2], "peg.clearance_mm": 3})
    assert from_text == from_dict


def test_ranges_drive_the_sampled_conditions() -> None:
    cfg = apply_overrides(BASE, ["hole.friction_scale=[4,4]", "grasp.angle_deg=[2,2]", "hole.y_offset_mm=[-7,-7]"])
    params = sample_params(cfg, "round", "all", seed=11)
    assert (params.friction_scale, params.grasp_angle_deg, params.hole_y_mm) == (4.0, 2.0, -7.0)
    params = sample_params(cfg, "round", "friction", seed=11)
    assert (params.friction_scale, params.grasp_angle_deg, params.hole_y_mm) == (4.0, 0.0, 0.0)


def test_unknown_keys_are_rejected_outside_overrides_too() -> None:
    """A config file / JSON with a typo fails loudly (extra="forbid"), not silently."""
    with pytest.raises(Exception, match="clearence_mm"):
        PegTaskConfig.model_validate({"peg": {"clearence_mm": 3}})
    with pytest.raises(Exception, match="nope"):
        PegTaskConfig.model_validate({"nope": {}})


def test_config_is_frozen() -> None:
    with pytest.raises(Exception):
        BASE.peg.clearance_mm = 5.0  # type: ignore[misc]


@pytest.mark.parametrize(("override", "key", "known"), [
    ("hole.frction_scale=[1,5]", "hole.frction_scale", ["friction_scale", "y_offset_mm", "depth_mm"]),
    ("pegs.clearance_mm=2", "pegs.clearance_mm", ["peg", "hole", "grasp", "wrist", "control", "camera", "sim"]),
    ("grasp.angle=[-5,5]", "grasp.angle", ["angle_deg", "depth_mm"]),
    ("peg.clearance_mm.inner=1", "peg.clearance_mm.inner", []),
])
def test_unknown_key_is_named_with_the_known_keys(override: str, key: str, known: list[str]) -> None:
    with pytest.raises(ConfigError) as exc:
        apply_overrides(BASE, [override])
    msg = str(exc.value)
    assert repr(key) in msg, msg
    for name in known:
        assert name in msg, msg


@pytest.mark.parametrize(("override", "key"), [
    ("peg.clearance_mm=abc", "peg.clearance_mm"),  # string for a float
    ("peg.clearance_mm=-1", "peg.clearance_mm"),  # negative clearance
    ("peg.clearance_mm=0", "peg.clearance_mm"),
    ("hole.friction_scale=[5,1]", "hole.friction_scale"),  # low > high
    ("grasp.angle_deg=[5,-5]", "grasp.angle_deg"),
    ("hole.friction_scale=[1,2,3]", "hole.friction_scale"),  # not a pair
    ("hole.friction_scale=3", "hole.friction_scale"),
    ("hole.y_offset_mm=[\"a\",1]", "hole.y_offset_mm"),
    ("camera.width=10", "camera.width"),
    ("hole.round_sides=7.5", "hole.round_sides"),
])
def test_bad_value_is_named(override: str, key: str) -> None:
    with pytest.raises(ConfigError) as exc:
        apply_overrides(BASE, [override])
    assert key in str(exc.value), str(exc.value)


def test_low_above_high_says_so() -> None:
    with pytest.raises(ConfigError, match=r"hole\.friction_scale.*low > high"):
        apply_overrides(BASE, ["hole.friction_scale=[5,1]"])


@pytest.mark.parametrize("text", ["peg.clearance_mm", "=3", "...=3", "", "peg.clearance_mm 2"])
def test_malformed_override_text(text: str) -> None:
    with pytest.raises(ConfigError) as exc:
        apply_overrides(BASE, [text])
    assert repr(text) in str(exc.value) or "key.path=value" in str(exc.value)


def test_config_errors_are_kintsugi_errors() -> None:
    assert issubclass(ConfigError, KintsugiError)
    with pytest.raises(KintsugiError):
        apply_overrides(BASE, ["nope=1"])


def test_parse_override_values() -> None:
    assert parse_override("a.b=[1,5]") == (["a", "b"], [1, 5])
    assert parse_override("a=2.5") == (["a"], 2.5)
    assert parse_override("a.b=hello world") == (["a", "b"], "hello world")
    assert parse_override("a.b=x=y") == (["a", "b"], "x=y")
