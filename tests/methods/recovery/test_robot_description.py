"""The robot's description: built from its own config, never from a trial's truth or its ranges,
and what the openai prompts state instead of fixed numbers."""

from __future__ import annotations

from importlib import resources

from tests.fake_openai_server import FakeOpenAIServer, content
from kintsugi.core.config import apply_overrides
from kintsugi.methods.recovery.prompting import robot_facts
from kintsugi.core.plugins import load_builtins
from kintsugi.core.runner import run_trial
from kintsugi.worlds.peg.config import PegTaskConfig
from kintsugi.worlds.peg.goals import load_goals
from kintsugi.worlds.peg.robot import PegRobot
from kintsugi.worlds.peg.world import PegWorld, TrialParams
from kintsugi.core.record import ReasonerSettings, TrialSpec

load_builtins()
# Randomization ranges with digits that appear nowhere else, so a leak would show.
RANGES = {"hole.y_offset_mm": [-23.4567, 23.4567], "grasp.angle_deg": [-6.7891, 6.7891],
          "hole.friction_scale": [1.2345, 4.3219]}
SECRETS = ("23.4567", "6.7891", "1.2345", "4.3219")


def _description(cfg: PegTaskConfig, params: TrialParams):  # noqa: ANN202
    world = PegWorld(cfg, params)
    try:
        return PegRobot(world, params.shape).description(load_goals())
    finally:
        world.close()


def test_description_is_the_same_whatever_the_trial_drew() -> None:
    cfg = apply_overrides(PegTaskConfig(), RANGES)
    a = _description(cfg, TrialParams(shape="square"))
    b = _description(cfg, TrialParams(shape="square", hole_y_mm=17.0, friction_scale=4.0, grasp_angle_deg=-4.5))
    assert a == b
    dumped = a.model_dump_json() + robot_facts(a)
    assert not any(s in dumped for s in SECRETS)


def test_description_follows_set() -> None:
    cfg = apply_overrides(PegTaskConfig(), {
        "peg.clearance_mm": 1.0, "peg.length_mm": 120, "wrist.hinge_to_grasp_mm": 30, "wrist.z_stiffness": 1500,
        "wrist.roll_stiffness": 0.8, "control.compression_limit_mm": 15, "control.pose_tol_mm": 0.5,
        "perception.align_tol_mm": 2.0, "hole.depth_mm": 50})
    d = _description(cfg, TrialParams(shape="rectangle"))
    assert (d.hole_clearance_mm, d.compliance_to_tip_mm, d.wrist_z_stiffness_n_per_mm) == (1.0, 150.0, 1.5)
    assert (d.wrist_roll_stiffness_nm_per_rad, d.compression_limit_mm, d.pose_tol_mm) == (0.8, 15.0, 0.5)
    assert (d.peg_width_mm, d.hole_width_mm, d.hole_depth_mm, d.vision.align_tol_mm) == (40.0, 41.0, 50.0, 2.0)
    facts = robot_facts(d)
    assert "The hole is 1 mm wider than the peg (41 mm)" in facts and "within about ±0.5 mm" in facts
    assert "atan(d / 150)" in facts and "more than 15 mm (22.5 N)" in facts


def test_prompt_files_state_no_robot_numbers_or_randomization() -> None:
    prompts = resources.files("kintsugi.methods.recovery").joinpath("prompts")
    for name in ("system", "judge", "analyze", "plan"):
        text = prompts.joinpath(f"{name}.md").read_text(encoding="utf-8")
        for fixed in ("±", "°", "2 mm", "42 mm", "1 mm", "140"):
            assert fixed not in text, (name, fixed)


def test_openai_requests_state_the_configured_robot_and_never_the_ranges(fake_openai: FakeOpenAIServer) -> None:
    fake_openai.push(*(content({"success": True, "explanation": "ok"}) for _ in range(3)))
    overrides = {"peg.clearance_mm": 1.0, **RANGES}
    spec = TrialSpec(task="peg-insertion", method="recovery", variant="square", condition="all", seed=0,
                     overrides=overrides, reasoner=ReasonerSettings(backend="openai", model="scripted",
                                                                     base_url=fake_openai.base_url, max_retries=0))
    rec = run_trial(spec)
    assert rec.error is None and len(fake_openai.requests) == 3
    for body in fake_openai.requests:
        system, user = body["messages"][0]["content"], body["messages"][1]["content"]
        text = system + "".join(p["text"] for p in user if p["type"] == "text")
        assert "# This robot" in text and "The hole is 1 mm wider than the peg (41 mm)" in text
        assert not any(s in text for s in SECRETS)
        assert "up to about" not in text and "2 mm wider" not in text  # the old fixed grasp range and clearance
