"""The Ray executor end to end on a local two-CPU Ray: one trial of each system, and a plugin task.

Each trial is a Ray task that runs `run_in_worker` (bootstrap the task's plugins, then the one
runner, `run_trial`) in a Ray worker process and ships the record back; every record must equal
the one the inline executor produces for the same spec. One Ray instance serves the whole module,
so the tests live in few functions (pytest-xdist would otherwise start one Ray per worker).
"""

from __future__ import annotations

import pytest

ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'kintsugi[ray]'; `make test` installs it)")

pytestmark = pytest.mark.slow  # a local Ray takes seconds to start

from kintsugi.campaign.plan import CampaignConfig, build_config, expand  # noqa: E402
from kintsugi.campaign.runner import run_campaign  # noqa: E402

# One cheap trial per system: A peg insertion, B tabletop pouring, C contact flipping (short MPPI budget).
SYSTEMS = [
    dict(task="peg-insertion", methods=["baseline"], variants=["round"], conditions=["none"], overrides={}),
    dict(task="pour-single", methods=["scripted"], variants=["default"], conditions=["none"], overrides={}),
    dict(task="flip-box", methods=["expert-fsm"], variants=["default"], conditions=["none"],
         overrides={"control.samples": 16, "control.episode_s": 2.5}),
]


@pytest.fixture(scope="module")
def local_ray():
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        yield ray
    finally:
        ray.shutdown()


def run_both(cfg: CampaignConfig, out) -> list[tuple]:
    """(ray record, inline record) per trial, in config order."""
    on_ray = run_campaign(cfg, out / "ray", workers=2, executor="ray", progress=False)
    inline = run_campaign(cfg, out / "inline", executor="inline", progress=False)
    assert [r.key for r in on_ray] == [r.key for r in inline] == [s.key for s in expand(cfg)]
    assert (out / "ray" / "results.jsonl").read_text().count("\n") == len(on_ray)
    return list(zip(on_ray, inline))


def test_ray_runs_one_trial_of_each_system_like_inline(local_ray, tmp_path):
    for system in SYSTEMS:
        [(record, inline)] = run_both(build_config(**system, trials=1), tmp_path / system["task"])
        assert record.error is None, f"{record.key}: {record.error}"
        assert record.physics_steps > 0 and record.sim_time > 0, record.key
        assert record.without_timings() == inline.without_timings(), f"{record.key}: ray and inline records differ"


def test_ray_workers_import_plugins_and_record_trial_errors(local_ray, tmp_path):
    cfg = CampaignConfig(task="fake-coin", methods=["recover"], variants=["fair", "raises"], conditions=["easy"],
                         trials=2, plugins=["tests.fake_tasks"])
    pairs = run_both(cfg, tmp_path)
    errors = {r.key: r.error for r, _ in pairs if r.error}
    assert list(errors) == ["fake-coin/recover/raises/easy/0"]
    assert "RuntimeError: fake failure" in errors["fake-coin/recover/raises/easy/0"]
    for record, inline in pairs:
        assert record.without_timings() == inline.without_timings(), f"{record.key}: ray and inline records differ"
