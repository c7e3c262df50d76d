"""LeRobot v3.0 and robomimic exports of a System A campaign (any system goes through the same step-level
recorder): the v3.0 files hold what LeRobot reads (info, episodes with their data and video spans, tasks,
stats), frames agree between the two formats, and a linear policy fitted on the HDF5 file round-trips."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

h5py = pytest.importorskip("h5py")
pq = pytest.importorskip("pyarrow.parquet")

from kintsugi.methods.policy.drivers.base import Driver  # noqa: E402


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    from kintsugi.campaign.plan import CampaignConfig
    from kintsugi.campaign.runner import run_campaign
    from kintsugi.export import export_campaign

    root = tmp_path_factory.mktemp("peg")
    cfg = CampaignConfig(task="peg-insertion", methods=["recovery"], variants=["round"], conditions=["all"],
                         trials=2, base_seed=0)
    run_campaign(cfg, root / "campaign", workers=1, executor="inline", progress=False)
    export_campaign(root / "campaign", "lerobot", root / "lr", fps=25)
    export_campaign(root / "campaign", "hdf5", root / "h5", fps=25)
    return root / "campaign", root / "lr", root / "h5" / "demo.hdf5"


def test_v3_layout_is_what_lerobot_reads(exported) -> None:
    import imageio.v2 as imageio

    _, lr, _ = exported
    info = json.loads((lr / "meta/info.json").read_text())
    assert info["codebase_version"] == "v3.0" and info["fps"] == 25 and info["total_episodes"] == 2
    feats = info["features"]
    assert feats["action"]["names"] == ["base_y", "base_z", "base_roll"]
    assert feats["observation.wrist_force"]["shape"] == [1]  # the F/T force is in the dataset
    assert feats["observation.state"]["names"] == ["base_pose.y", "base_pose.z", "base_pose.roll", "wrist_force"]
    data = pq.read_table(lr / info["data_path"].format(chunk_index=0, file_index=0)).to_pydict()
    eps = pq.read_table(lr / "meta/episodes/chunk-000/file-000.parquet").to_pydict()
    assert len(data["index"]) == info["total_frames"] == sum(eps["length"])
    assert data["index"] == list(range(info["total_frames"]))
    assert eps["dataset_from_index"] == [0, eps["length"][0]] and eps["dataset_to_index"][-1] == info["total_frames"]
    key = "observation.images.scene"
    assert eps[f"videos/{key}/from_timestamp"][1] == pytest.approx(eps["length"][0] / 25)
    reader = imageio.get_reader(lr / info["video_path"].format(video_key=key, chunk_index=0, file_index=0))
    count, shape = 0, None
    for frame in reader:
        count, shape = count + 1, frame.shape
    reader.close()
    assert count == info["total_frames"] and shape == tuple(feats[key]["shape"])
    tasks = pq.read_table(lr / "meta/tasks.parquet")
    assert tasks.column("task_index").to_pylist() == [0] and b"pandas" in tasks.schema.metadata
    stats = json.loads((lr / "meta/stats.json").read_text())
    assert stats["action"]["count"] == [info["total_frames"]] and len(stats[key]["mean"]) == 3


def test_hdf5_agrees_with_lerobot_frame_for_frame(exported) -> None:
    _, lr, h5 = exported
    data = pq.read_table(lr / "data/chunk-000/file-000.parquet").to_pydict()
    with h5py.File(h5) as f:
        a = f["data/demo_0/actions"][:]
        force = f["data/demo_0/obs/wrist_force"][:]
        assert json.loads(f["data"].attrs["env_args"])["type"] == "kintsugi-peg"
    n = len(a)
    assert np.allclose(np.array(data["action"][:n]), a, atol=1e-6)
    assert np.allclose(np.array(data["observation.wrist_force"][:n]), force.reshape(-1), atol=1e-4)  # a scalar column


def test_linear_policy_fits_and_round_trips(exported, tmp_path: Path) -> None:
    from kintsugi.methods.policy.policies import load_policy
    from kintsugi.methods.policy.train import fit_hdf5

    _, _, h5 = exported
    p = fit_hdf5(h5, ("base_pose", "wrist_force"), bases=20, demos="all")
    with h5py.File(h5) as f:
        x = np.hstack([f["data/demo_0/obs/base_pose"][:], f["data/demo_0/obs/wrist_force"][:]])
        a = f["data/demo_0/actions"][:]
    err = np.abs(p.predict(x, np.arange(len(x))) - a).mean(0)
    assert err[0] < 0.01 and err[1] < 0.01  # within a centimetre on average
    again = load_policy(str(p.save(tmp_path / "bc.npz")))
    assert np.allclose(again.predict(x[:5], np.arange(5)), p.predict(x[:5], np.arange(5)))


def test_quaternions_stay_on_one_hemisphere() -> None:
    class D(Driver):
        action_low = action_high = None  # type: ignore[assignment]
        apply = tick = command = features = observe = render = record_ticks = None  # type: ignore[assignment]
        physics_steps = sim_time = 0  # type: ignore[assignment]

    d = D.__new__(D)
    Driver.__init__(d)
    q = np.array([0.1, 0.2, 0.3, -0.927])
    first = d.continuous("arm", q, 3)
    assert first[3] > 0
    assert np.allclose(d.continuous("arm", -first, 3), first)  # the flipped sign comes back
    assert np.allclose(d.continuous("arm", first, 3), first)


def test_trajectory_export_replays_through_the_policy_method(exported, tmp_path: Path) -> None:
    from kintsugi.campaign.store import ResultStore
    from kintsugi.core.record import TrialSpec
    from kintsugi.core.runner import run_trial
    from kintsugi.export import export_campaign

    campaign, _, _ = exported
    rep = export_campaign(campaign, "trajectory", tmp_path / "traj", trials="seed=1")
    [stored] = [r for r in ResultStore(campaign).read() if r.seed == 1]
    path = tmp_path / "traj" / (stored.key.replace("/", "__") + ".npz")
    assert [e.key for e in rep.exported] == [stored.key] and path.is_file()
    again = run_trial(TrialSpec(task=stored.task, method="policy", variant=stored.variant,
                                condition=stored.condition, seed=1, overrides={"method.path": str(path)}))
    assert (again.physics_steps, again.success, again.framework_success) == (
        stored.physics_steps, stored.success, stored.framework_success)


@pytest.mark.slow
def test_an_hdf5_demo_at_the_control_rate_replays_step_for_step(exported, tmp_path: Path) -> None:
    from kintsugi.campaign.store import ResultStore
    from kintsugi.core.errors import ConfigError
    from kintsugi.core.record import TrialSpec
    from kintsugi.core.runner import run_trial
    from kintsugi.export import export_campaign
    from kintsugi.methods.policy.policies import load_policy

    campaign, _, h5_at_25 = exported
    with pytest.raises(ConfigError, match="export with --fps 250"):
        load_policy(f"{h5_at_25}#demo_0")
    export_campaign(campaign, "hdf5", tmp_path / "full", trials="seed=0", fps=250)
    [stored] = [r for r in ResultStore(campaign).read() if r.seed == 0]
    again = run_trial(TrialSpec(task=stored.task, method="policy", variant=stored.variant, condition=stored.condition,
                                seed=0, overrides={"method.path": f"{tmp_path / 'full' / 'demo.hdf5'}#demo_0"}))
    assert (again.physics_steps, again.success, again.framework_success) == (
        stored.physics_steps, stored.success, stored.framework_success)
