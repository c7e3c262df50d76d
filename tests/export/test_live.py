"""Watching a trial live: the page's frames and status follow the trial and are served over loopback HTTP while
it runs; a watched trial is the same trial; `run`/`watch --viewer` sync MuJoCo's viewer every control period where
a display exists and are a one-line error before the trial where none does."""

from __future__ import annotations

import json
import urllib.request
from pathlib import Path

import cv2
import pytest
from typer.testing import CliRunner

from kintsugi.core.record import TrialSpec
from kintsugi.core.runner import run_trial
from kintsugi.export.live import LivePage


def test_live_page_follows_the_trial_and_is_served(tmp_path: Path) -> None:
    spec = TrialSpec(task="peg-insertion", method="baseline", variant="round", condition="none", seed=0)
    page = LivePage(tmp_path / "live", spec.key, every_s=0.5, port=0)
    try:
        watched = run_trial(spec, echo=page.echo, attach=page.attach)
        status = json.loads(urllib.request.urlopen(page.url + "status.json", timeout=10).read())
        html = urllib.request.urlopen(page.url, timeout=10).read().decode()
    finally:
        page.finish()
    plain = run_trial(spec)
    assert (watched.physics_steps, watched.success) == (plain.physics_steps, plain.success)
    assert status["title"] == spec.key and status["frame"] >= int(plain.sim_time / 0.5)  # one every 0.5 s
    assert "kintsugi live" in html and any("approach" in line and "[" not in line for line in status["story"])
    frame = cv2.imread(str(tmp_path / "live" / "frame.jpg"))
    assert frame.shape == (240, 320, 3) and frame.std() > 1.0
    final = json.loads((tmp_path / "live" / "status.json").read_text())
    assert final["done"] is True and final["step"] == plain.physics_steps // 4  # every control period seen


@pytest.mark.parametrize("command", ["watch", "run"])
def test_viewer_without_a_display_is_a_clear_error(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                   command: str) -> None:
    from kintsugi.cli import app

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    extra = ["--record", str(tmp_path / "r.json")] if command == "run" else []
    result = CliRunner().invoke(app, [command, "peg-insertion", "--viewer", *extra])
    assert result.exit_code == 2 and "needs a display" in result.output
    assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "r.json").exists()  # before the trial


class _FakeHandle:
    """Stands in for `mujoco.viewer.launch_passive`'s handle where a display exists (none does here)."""

    def __init__(self, model, data) -> None:  # noqa: ANN001
        self.model, self.data, self.syncs, self.closed = model, data, 0, False

    def is_running(self) -> bool:
        return not self.closed

    def sync(self) -> None:
        self.syncs += 1

    def close(self) -> None:
        self.closed = True


def test_run_viewer_syncs_every_control_period_where_a_display_exists(monkeypatch: pytest.MonkeyPatch,
                                                                     tmp_path: Path) -> None:
    import mujoco.viewer

    from kintsugi.cli import app

    handles: list[_FakeHandle] = []
    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.setattr(mujoco.viewer, "launch_passive", lambda m, d: handles.append(_FakeHandle(m, d)) or handles[-1])
    result = CliRunner().invoke(app, ["run", "peg-insertion", "--method", "baseline", "--condition", "none",
                                      "--viewer", "--record", str(tmp_path / "r.json")])
    assert result.exit_code == 0, result.output
    record = json.loads((tmp_path / "r.json").read_text())
    plain = run_trial(TrialSpec(task="peg-insertion", method="baseline", variant="round", condition="none", seed=0))
    (h,) = handles
    assert h.closed and h.syncs == plain.physics_steps // 4  # one per control period (4 physics steps each)
    assert record["success"] == plain.success and record["physics_steps"] == plain.physics_steps  # same trial
