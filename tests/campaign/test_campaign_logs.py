"""What a campaign tells a log file and its report beyond the tables: pace, videos, provenance."""

from __future__ import annotations

from pathlib import Path

from kintsugi.campaign.report import _videos, machine_info
from kintsugi.campaign.runner import progress_line
from kintsugi.core.record import TrialRecord


def _rec(video: str | None = None) -> TrialRecord:
    return TrialRecord(key="t/m/v/c/0", task="t", method="m", variant="v", condition="c", seed=0, success=True,
                       wall_time=1.5, video=video)


def test_a_log_line_says_elapsed_and_time_left() -> None:
    line = progress_line(_rec(), 3, 10, 3, 0, elapsed_s=75.0, eta_s=3725.0)
    assert line.endswith("[1:15 elapsed, ~1:02:05 left]") and line.startswith("3/10 t/m/v/c/0: success")
    assert "elapsed" not in progress_line(_rec(), 3, 10, 3, 0)


def test_the_report_links_videos_relative_to_itself_and_names_the_commit(tmp_path: Path) -> None:
    (tmp_path / "videos").mkdir()
    (tmp_path / "videos" / "a.mp4").write_bytes(b"")
    recs = [_rec(str(tmp_path / "videos" / "a.mp4")), _rec(str(tmp_path / "videos" / "gone.mp4")), _rec()]
    assert _videos(tmp_path, recs) == [("t/m/v/c/0", "videos/a.mp4")]
    assert machine_info()["commit"]


def test_a_log_gets_a_heartbeat_while_a_trial_runs_and_none_after() -> None:
    import io
    import time

    from rich.console import Console

    from kintsugi.campaign.runner import _Heartbeat

    out = io.StringIO()
    console = Console(file=out, force_terminal=False, width=200)
    with _Heartbeat(console, total=4, started=time.monotonic(), every_s=0.2) as beat:
        time.sleep(0.5)  # a long trial: no record for more than the period
        beat.done(1)
        time.sleep(0.1)  # a trial just finished: no heartbeat yet
        lines = out.getvalue().splitlines()
    assert len(lines) >= 1 and all(line.startswith("0/4 still running: [0:00 elapsed]") for line in lines)
    time.sleep(0.3)
    assert out.getvalue().splitlines() == lines  # stopped with the campaign
