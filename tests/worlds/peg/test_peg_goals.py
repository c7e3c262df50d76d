"""The taught goals are checked once per config: a goal image must show a real insertion.

With a stiffer roll spring the shipped goals leave the round peg on the rim in
the default condition; its "goal image" would show a failure, so the context
refuses with the command that re-teaches, and re-taught goals are accepted.
"""

from __future__ import annotations

import json

import pytest

from kintsugi.core.config import apply_overrides
from kintsugi.core.errors import ConfigError
from kintsugi.core.plugins import load_builtins
from kintsugi.core.runner import run_trial
from kintsugi.worlds.peg import context as context_module
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.context import PegContext, config_changes
from kintsugi.worlds.peg.goals import load_goals
from kintsugi.core.record import TrialSpec

load_builtins()
STIFF_ROLL = "wrist.roll_stiffness=1.5"


def test_goals_that_no_longer_insert_are_an_error_naming_the_config_and_the_fix() -> None:
    ctx = PegContext(cfg=apply_overrides(PegTaskConfig(), [STIFF_ROLL]), shape="round")
    with pytest.raises(ConfigError) as err:
        ctx.goal_images()
    text = str(err.value)
    assert "do not insert the round peg in the default condition with wrist.roll_stiffness=1.5" in text
    assert f"bench/teach_goals.py --set {STIFF_ROLL} --shapes round --out goals.json" in text
    assert "--set control.goals_file=goals.json" in text


def test_the_check_runs_once_per_config_and_shape() -> None:
    cfg = apply_overrides(PegTaskConfig(), ["scoring.min_depth_fraction=0.45"])  # a config no other test uses
    before = context_module._goal_images.cache_info()
    for _ in range(3):
        images = PegContext(cfg=cfg, shape="square").goal_images()
    after = context_module._goal_images.cache_info()
    assert set(images) == {"approach", "contact", "fit", "align", "insert"}
    assert (after.misses - before.misses, after.hits - before.hits) == (1, 2)


def test_retaught_goals_are_used_and_accepted(tmp_path) -> None:  # noqa: ANN001
    # What `bench/teach_goals.py --set wrist.roll_stiffness=1.5 --shapes round --out ...` finds.
    goals = {s: dict(v) for s, v in load_goals().items()}
    goals["fit"]["y"], goals["align"]["y"] = 6.0, -5.5
    path = tmp_path / "goals.json"
    path.write_text(json.dumps(goals))
    overrides = {"wrist.roll_stiffness": 1.5, "control.goals_file": str(path)}
    ctx = PegContext(cfg=apply_overrides(PegTaskConfig(), overrides), shape="round")
    assert ctx.goals["fit"] == {"y": 6.0}
    assert "insert" in ctx.goal_images()
    rec = run_trial(TrialSpec(
        task="peg-insertion", method="recovery", variant="round", condition="none", seed=0, overrides=overrides))
    assert rec.error is None and rec.success and rec.framework_success
    assert rec.skills[2].goal["y"] == pytest.approx(6.0)  # fit ran the re-taught goal


def test_config_changes_lists_overrides_as_set_takes_them() -> None:
    cfg = apply_overrides(PegTaskConfig(), [STIFF_ROLL, "grasp.angle_deg=[-2,2]"])
    assert config_changes(cfg) == ["grasp.angle_deg=[-2.0,2.0]", STIFF_ROLL]
    assert config_changes(PegTaskConfig()) == []
