"""System C's tasks end to end: registration, method/task compatibility, a scored expert trial, honesty."""

from __future__ import annotations

import kintsugi  # noqa: F401 - sets MUJOCO_GL before mujoco is imported
import pytest

from kintsugi.core.plugins import load_builtins
from kintsugi.core.registry import METHODS, TASKS
from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.methods.expert.designs import EXPERTS

load_builtins()
CONTACT = [e.name for e in TASKS if "contact" in e.tags]


def _spec(task: str, method: str, seed: int = 0, condition: str = "random", **kw) -> TrialSpec:  # noqa: ANN003
    return TrialSpec(task=task, method=method, variant="default", condition=condition, seed=seed, **kw)


def test_tasks_and_methods_are_registered_with_their_tags() -> None:
    assert "pick-box" in CONTACT
    for name in ("expert", "expert-fsm"):
        assert {"system-c", "oracle-physics"} <= METHODS.get(name).tags
    for task in CONTACT:
        t = TASKS.get(task).factory()
        reference = "expert-fsm" if task in EXPERTS else "coral"  # a plugin's task may have no expert
        assert t.reference_method == reference and "random" in t.conditions and "none" in t.conditions


def test_other_systems_methods_are_refused_by_name() -> None:
    record = run_trial(_spec("pick-box", "scripted"))
    assert record.error and "does not run task 'pick-box'" in record.error and "expert-fsm" in record.error
    record = run_trial(TrialSpec(task="pick-box", method="expert-fsm", variant="round", condition="none", seed=0))
    assert record.error and "unknown variant 'round'" in record.error and "default" in record.error
    record = run_trial(_spec("pick-box", "expert-fsm", overrides={"box.no_such": 1}))
    assert record.error and "box.no_such" in record.error


@pytest.mark.slow
def test_expert_fsm_picks_the_box_and_logs_every_stage() -> None:
    record = run_trial(_spec("pick-box", "expert-fsm", seed=2))
    assert record.error is None, record.error
    assert record.success and record.framework_success
    assert [s.skill for s in record.skills] == ["reach", "descend", "grasp", "lift", "hold"]
    assert all(s.reached for s in record.skills)
    assert record.task_figures["pinched"] and record.task_figures["lowest_z_m"] >= 0.05
    assert record.params["box.mass_kg"] != pytest.approx(0.25)  # a randomized draw


def test_a_box_left_on_the_table_is_a_failure_whatever_the_method_says() -> None:
    # half a second is too short to reach the box: the ground truth must say failure
    record = run_trial(_spec("pick-box", "expert-fsm", seed=2, overrides={"control.episode_s": 0.5}))
    assert record.error is None, record.error
    assert not record.success and not record.framework_success
    assert record.task_figures["lowest_z_m"] < 0.01 and not record.task_figures["pinched"]
    assert record.skills and not record.skills[-1].reached


def test_every_paper_task_is_registered_with_both_experts() -> None:
    from kintsugi.methods.expert.designs import EXPERTS

    paper = {"push-pick-board", "pick-box", "pick-clutter", "push-force", "flip-box", "flip-wall"}
    assert paper <= set(CONTACT)
    assert paper <= set(EXPERTS)


@pytest.mark.slow
def test_plan_plot_is_a_png_with_the_three_series(tmp_path) -> None:  # noqa: ANN001
    from kintsugi.worlds.contact.plot import PlanSeries, plot_path_for, plot_plan

    series = PlanSeries()
    for i in range(20):
        series.add(0.1 * i, "push" if i < 10 else "lift", 5.0 / (i + 1), 0.5, 0.1)
    series.add(2.0, "lift", float("inf"), 0.5, 0.1)  # an all-invalid step is skipped, not plotted as inf
    out = plot_plan(series, plot_path_for(tmp_path / "trial.mp4"), title="t")
    assert out.name == "trial.plan.png" and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import imageio.v3 as iio

    image = iio.imread(out)
    assert image.shape[0] > 400 and image.shape[1] > 600


@pytest.mark.slow
def test_a_contact_video_comes_with_its_planner_plot(tmp_path) -> None:  # noqa: ANN001
    video = tmp_path / "pick.mp4"
    record = run_trial(TrialSpec(task="pick-box", method="expert-fsm", variant="default", condition="none", seed=0,
                                 overrides={"control.samples": 8, "control.episode_s": 0.6}, video=str(video)))
    assert record.error is None, record.error
    assert record.video and video.exists()
    plot = tmp_path / "pick.plan.png"
    assert plot.exists() and any(e.kind == "plot" and str(plot) in e.detail for e in record.events)
