"""A LeRobot v3.0 export of a System A campaign (and, in the slow set, B and C) loads in LeRobot's own
`LeRobotDataset`: frame and episode counts, feature names and shapes, decoded video frames match the export.

LeRobot needs torch and pins an older one than this machine's CPU build, so it lives in an optional
environment, `.venv-lerobot`: `make lerobot-check` installs it without its pins and runs these tests with
`KINTSUGI_LEROBOT_PYTHON` naming its interpreter (or another one that has lerobot); without that variable
they skip, saying so, and `make test` stays within its time."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("pyarrow")
ROOT = Path(__file__).resolve().parents[2]
PYTHON = Path(os.environ.get("KINTSUGI_LEROBOT_PYTHON", ""))


def _lerobot() -> Path:
    if not os.environ.get("KINTSUGI_LEROBOT_PYTHON"):
        pytest.skip("the LeRobot load check runs with `make lerobot-check` (KINTSUGI_LEROBOT_PYTHON unset)")
    if not PYTHON.exists():
        pytest.skip(f"no LeRobot environment at {PYTHON} (make lerobot-check installs one)")
    probe = subprocess.run([str(PYTHON), "-c", "import lerobot.datasets.lerobot_dataset"], capture_output=True,
                           text=True, timeout=300)
    if probe.returncode != 0:
        pytest.skip(f"LeRobot does not import in {PYTHON}: {probe.stderr.strip().splitlines()[-1:]}")
    return PYTHON


def _export(tmp_path: Path, task: str, method: str, variant: str, condition: str, trials: int, fps: float,
            overrides: dict | None = None) -> Path:
    from kintsugi.campaign.plan import CampaignConfig
    from kintsugi.campaign.runner import run_campaign
    from kintsugi.export import export_campaign

    camp = tmp_path / "campaign"
    cfg = CampaignConfig(task=task, methods=[method], variants=[variant], conditions=[condition], trials=trials,
                         base_seed=0, overrides=overrides or {})
    run_campaign(cfg, camp, workers=1, executor="inline", progress=False)
    rep = export_campaign(camp, "lerobot", tmp_path / "ds", fps=fps)
    assert rep.exported and not rep.refused
    return tmp_path / "ds"


def _check(python: Path, root: Path) -> None:
    out = subprocess.run([str(python), str(ROOT / "tests/export/lerobot_check.py"), str(root)], capture_output=True,
                         text=True, timeout=600, env={**os.environ, "HF_HUB_OFFLINE": "1", "HF_DATASETS_OFFLINE": "1"})
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    info = json.loads((root / "meta/info.json").read_text())
    assert got["codebase_version"] == info["codebase_version"] == "v3.0"
    assert got["frames"] == info["total_frames"] and got["episodes"] == info["total_episodes"]
    assert set(info["features"]) <= set(got["features"])
    for key, feat in info["features"].items():
        if feat["dtype"] == "video":
            h, w, c = feat["shape"]
            assert got["shapes"][key] == [c, h, w] and got["video_mean"][key] > 0.05  # decoded, not black
        elif feat["shape"] != [1]:
            assert got["shapes"][key] == feat["shape"], key
    assert got["last_episode"] == info["total_episodes"] - 1


def test_peg_export_loads_in_lerobot(tmp_path: Path) -> None:
    python = _lerobot()
    _check(python, _export(tmp_path, "peg-insertion", "recovery", "round", "all", 2, 25))


@pytest.mark.slow
def test_tabletop_and_contact_exports_load_in_lerobot(tmp_path: Path) -> None:
    python = _lerobot()
    _check(python, _export(tmp_path / "b", "pour-single", "agentchord", "default", "drop", 1, 10,
                           {"disturbance.drop_p": 0.1}))
    _check(python, _export(tmp_path / "c", "push-force", "expert-fsm", "default", "all", 1, 10))
