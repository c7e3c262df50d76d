"""Watching a trial live: the page's frames and status follow the trial and are served over loopback HTTP while
it runs; a watched trial is the same trial; --viewer without a display is a one-line error."""

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


def test_viewer_without_a_display_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    from kintsugi.cli import app

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    result = CliRunner().invoke(app, ["watch", "peg-insertion", "--viewer"])
    assert result.exit_code == 2 and "needs a display" in result.output
