"""Trajectory export: a one-trial agentchord campaign with a drop (pour-single, seed 22 drops the bottle during
the lift and the pre-compiled branch re-grasps; later drops may follow, as the actions' draws fall), re-run and written as robomimic HDF5 and LeRobot v2.1;
files read back. A record the re-run does not reproduce is refused; bad filters and rates are one-line errors."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from kintsugi.core.errors import ConfigError, KintsugiError
from kintsugi.core.record import SkillLog, TrialRecord
from kintsugi.methods.agentchord.method import RunFigures

h5py = pytest.importorskip("h5py")
pq = pytest.importorskip("pyarrow.parquet")

SEED = 22
KEY = f"pour-single/agentchord/default/drop/{SEED}"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from kintsugi.campaign.plan import CampaignConfig
    from kintsugi.campaign.runner import run_campaign

    out = tmp_path_factory.mktemp("campaign")
    cfg = CampaignConfig(task="pour-single", methods=["agentchord"], variants=["default"], conditions=["drop"],
                         trials=1, base_seed=SEED, overrides={"disturbance.drop_p": 0.1})
    [record] = run_campaign(cfg, out, workers=1, executor="inline", progress=False)
    assert record.error is None and record.success and record.transitions, "the fixture trial must recover"
    return out


@pytest.fixture(scope="module")
def hdf5_export(campaign: Path, tmp_path_factory: pytest.TempPathFactory):
    from kintsugi.export import export_campaign

    out = tmp_path_factory.mktemp("h5") / "ds"
    return export_campaign(campaign, "hdf5", out, trials="method=agentchord,recovered", fps=10)


def _record(campaign: Path) -> TrialRecord:
    from kintsugi.campaign.store import ResultStore

    [r] = ResultStore(campaign).read()
    return r


@pytest.mark.slow
def test_hdf5_holds_observations_actions_and_both_segments(campaign: Path, hdf5_export) -> None:
    rep = hdf5_export
    assert [e.key for e in rep.exported] == [KEY] and not rep.refused
    rec = _record(campaign)
    steps = RunFigures.of(rec).episode_steps
    with h5py.File(rep.path) as f:
        demo = f["data/demo_0"]
        t = int(demo.attrs["num_samples"])
        assert t == steps // 10 == rep.exported[0].frames and f["data"].attrs["total"] == t
        assert demo["actions"].shape == (t, 14)
        for cam in ("top", "front"):
            img = demo[f"obs/{cam}_image"]
            assert img.shape == (t, 240, 320, 3) and img.dtype == np.uint8
            assert demo[f"next_obs/{cam}_image"].shape == img.shape
            assert np.array_equal(demo[f"next_obs/{cam}_image"][0], img[1])
        assert demo["obs/right_joint_pos"].shape == (t, 6) and demo["obs/left_eef_quat"].shape == (t, 4)
        quat = demo["obs/right_eef_quat"][:]
        assert np.allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-6)
        # Position control tracks the command: the right arm's joints one frame later are near its targets.
        act = demo["actions"][:]
        q_next = demo["next_obs/right_joint_pos"][:]
        assert np.degrees(np.abs(act[:, 7:13] - q_next).mean()) < 2.0
        assert set(np.unique(act[:, [6, 13]])) <= {0.0, 1.0}
        assert demo["dones"][-1] == 1 and demo["dones"][:-1].sum() == 0 and demo["rewards"][-1] == 1.0

        vocab = json.loads(f["data"].attrs["label_vocab"])
        recovery = demo["labels/recovery"][:].astype(bool)
        edges = [vocab["edge"][i] for i in demo["labels/edge"][:]]
        actions = [vocab["action"][i] for i in demo["labels/action"][:]]
        assert recovery.any() and (~recovery).any()
        assert all(e.startswith("re.") for e, r in zip(edges, recovery) if r)
        assert not any(e.startswith("re.") for e, r in zip(edges, recovery) if not r)
        first = int(np.flatnonzero(recovery)[0])
        last = first + int(np.argmin(recovery[first:])) - 1  # the end of the first recovery segment
        assert all(e.startswith("re.e2_lift.drop") for e in edges[first:last + 1]), "the lift's drop, recovered"
        assert edges[first - 1] == "e2_lift" and edges[last + 1] == "e3_carry_over"
        assert actions[first] == "open_gripper" and act[first, 13] == 0.0  # the branch lets go first
        assert "grasp" in actions[first:last + 1]  # ... then re-grasps the dropped bottle
        drop_t = next(e.t for e in rec.events if e.kind == "disturbance")
        assert (first + 1) * 10 * 0.01 >= drop_t - 0.05  # never labelled recovery before the drop
        numbers = demo["labels/action_number"][:]
        assert (np.diff(numbers) >= 0).all() and numbers[-1] < len(rec.skills)
        assert [n.decode() for n in f["mask/recovered"][:]] == ["demo_0"] and len(f["mask/nominal"][:]) == 0
        env = json.loads(f["data"].attrs["env_args"])
        assert env["env_name"] == "pour-single" and env["env_kwargs"]["fps"] == 10
        assert "states" not in demo, "simulator state is ground truth, not an observation"
    manifest = json.loads((rep.out / "export.json").read_text())
    assert manifest["format"] == "hdf5" and manifest["exported"][0]["key"] == KEY


@pytest.mark.slow
def test_lerobot_layout_reads_back_and_agrees_with_hdf5(campaign: Path, hdf5_export, tmp_path: Path) -> None:
    import imageio.v2 as imageio

    from kintsugi.export import export_campaign

    out = tmp_path / "lr"
    rep = export_campaign(campaign, "lerobot-v2.1", out, fps=5)
    assert [e.key for e in rep.exported] == [KEY]
    info = json.loads((out / "meta/info.json").read_text())
    assert info["codebase_version"] == "v2.1" and info["fps"] == 5 and info["total_episodes"] == 1
    assert info["total_videos"] == 2 and info["features"]["action"]["shape"] == [14]
    table = pq.read_table(out / info["data_path"].format(episode_chunk=0, episode_index=0)).to_pydict()
    t = len(table["frame_index"])
    assert t == info["total_frames"] == rep.exported[0].frames
    assert [json.loads(x) for x in (out / "meta/episodes.jsonl").read_text().splitlines()][0]["length"] == t
    assert json.loads((out / "meta/tasks.jsonl").read_text())["task"].startswith("Pour water")
    assert table["frame_index"] == list(range(t)) and table["index"] == list(range(t))
    assert np.allclose(table["timestamp"], np.arange(t) / 5, atol=1e-6)
    assert table["next.done"][-1] and not any(table["next.done"][:-1]) and table["next.success"][-1]
    assert len(table["observation.state"][0]) == 14 and len(table["observation.eef_pose"][0]) == 14
    rec = np.array(table["segment.recovery"])
    assert rec.any() and (~rec).any()
    names = json.loads((out / "meta/segments.json").read_text())["segment.edge_index"]
    recovered = {names[i] for i, r in zip(table["segment.edge_index"], rec) if r}
    assert recovered <= {n for n in names if n.startswith("re.")}
    assert any(n.startswith("re.e2_lift.drop") for n in recovered)
    stats = json.loads((out / "meta/episodes_stats.jsonl").read_text())["stats"]
    assert stats["action"]["count"] == [t] and len(stats["observation.images.top"]["mean"]) == 3

    # Same trial, same commands: frame j at 5 fps is frame 2j + 1 at 10 fps (the command ending the frame).
    with h5py.File(hdf5_export.path) as f:
        h5_actions = f["data/demo_0/actions"][:]
        h5_top = f["data/demo_0/obs/top_image"][:]
    lr_actions = np.array(table["action"], dtype=np.float32)
    assert np.allclose(lr_actions, h5_actions[1::2][:t].astype(np.float32), atol=1e-6)
    video = out / info["video_path"].format(episode_chunk=0, video_key="observation.images.top", episode_index=0)
    frames = [f for f in imageio.get_reader(video)]
    assert len(frames) == t and frames[0].shape == (240, 320, 3)
    for j in (0, t // 2, t - 1):  # lossy video, same picture as the lossless HDF5 frame 2j
        assert np.abs(frames[j].astype(float) - h5_top[2 * j]).mean() < 6.0


@pytest.mark.slow
def test_a_record_the_rerun_does_not_reproduce_is_refused(campaign: Path, tmp_path: Path) -> None:
    from kintsugi.export import export_campaign

    bad = tmp_path / "tampered"
    shutil.copytree(campaign, bad)
    r = _record(campaign)
    forged = r.model_copy(update={"physics_steps": r.physics_steps + 5,
                                  "skills": [*r.skills[:-1], r.skills[-1].model_copy(update={"reached": False})]})
    (bad / "results.jsonl").write_text(forged.model_dump_json() + "\n")
    with pytest.raises(KintsugiError, match=r"did not reproduce its record: physics_steps .*; actions") as exc:
        export_campaign(bad, "hdf5", tmp_path / "out", fps=5)
    assert KEY in str(exc.value)
    assert not (tmp_path / "out" / "demo.hdf5").exists()


@pytest.mark.slow
def test_bad_filters_rates_and_outputs_are_clear_errors(campaign: Path, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from kintsugi.cli import app
    from kintsugi.export import export_campaign

    for trials, words in (("colour=red", "unknown field 'colour'"), ("recoverd", "unknown flag 'recoverd'"),
                          ("seed=3-x", "seeds are integers"), ("seed=5-2", "is empty"),
                          ("recovered,nominal", "contradictory"), ("method=rekep", "no trial of"),
                          ("method=,seed=3", "empty value"), ("seed=3,,ok", "empty term")):
        with pytest.raises(KintsugiError, match=words):
            export_campaign(campaign, "hdf5", tmp_path / "x", trials=trials)
    with pytest.raises(ConfigError, match="does not divide the control rate 100 Hz"):
        export_campaign(campaign, "lerobot", tmp_path / "x", fps=7)
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "keep.txt").write_text("mine")
    with pytest.raises(ConfigError, match="not empty"):
        export_campaign(campaign, "lerobot", busy)
    with pytest.raises(KintsugiError, match="not found"):
        export_campaign(tmp_path / "nowhere", "hdf5", tmp_path / "x")
    res = CliRunner().invoke(app, ["export", str(campaign), "--format", "hdf5", "--out", str(tmp_path / "y"),
                                   "--trials", "colour=red"])
    assert res.exit_code == 2 and "unknown field 'colour'" in res.output
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_filter_terms_select_by_key_fields_and_what_the_method_reported() -> None:
    from kintsugi.export.select import parse_filter

    def rec(method: str, seed: int, recovered: bool, success: bool = True) -> TrialRecord:
        skills = [SkillLog(skill="grasp", goal={}, terminal={}, reached=True, recovery=recovered)]
        return TrialRecord(key=f"t/{method}/default/drop/{seed}", task="t", method=method, variant="default",
                           condition="drop", seed=seed, success=success, skills=skills)

    rs = [rec("agentchord", 0, False), rec("agentchord", 1, True), rec("rekep", 2, True, False), rec("doremi", 7, False)]
    pick = lambda text: [r.seed for r in rs if parse_filter(text).keeps(r)]  # noqa: E731
    assert pick("") == [0, 1, 2, 7] and pick(None) == [0, 1, 2, 7]
    assert pick("recovered") == [1, 2] and pick("nominal") == [0, 7] and pick("failed") == [2]
    assert pick("method=agentchord|rekep,seed=1-2") == [1, 2] and pick("method=d*,seed=0|7") == [7]
    assert pick("method=*chord,seed=0|7") == [0]
    assert pick("key=*/drop/1") == [1] and pick("condition=drop,success,recovered") == [1]
