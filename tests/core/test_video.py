"""Trial videos: the status band sits below the scene, long labels wrap (never cut), and every
system's trial ends on the scored outcome (the runner calls `finish`)."""

from __future__ import annotations

from pathlib import Path

import imageio.v2 as imageio
import numpy as np

from kintsugi.core.plugins import load_builtins
from kintsugi.core.record import TrialSpec
from kintsugi.core.registry import METHODS
from kintsugi.core.runner import run_trial
from kintsugi.core.video import BAND_PX, VideoRecorder, band_height, wrap

SCENE = np.full((240, 320, 3), 90, dtype=np.uint8)


def text_rows(frame: np.ndarray, top: int = 240) -> int:
    """How many pixel rows of the band hold any text."""
    return int((frame[top:].max(axis=(1, 2)) > 0).sum())


def test_video_overlay_sits_below_the_scene_and_ends_with_the_scored_outcome(tmp_path: Path) -> None:
    rec = VideoRecorder(fps=10, scale=1, hold_s=0.2)
    rec.status("CF4 insert")
    rec.add(SCENE, 0.0)
    rec.status("CF4 insert", "last verdict: insert SUCCESS")  # ends the run: held, so it is seen
    assert len(rec.frames) == 1 + rec.hold_frames
    rec.finish("outcome: ground truth G SUCCESS, framework F success", True)
    assert len(rec.frames) == 1 + 3 * rec.hold_frames
    for frame in rec.frames[:-2 * rec.hold_frames]:
        assert frame.shape == (240 + BAND_PX, 320, 3)
    for frame in rec.frames:  # the outcome is wider than 320 px: it wraps, and its band grows
        assert frame.shape[1:] == (320, 3) and frame.shape[0] >= 240 + BAND_PX
        assert (frame[:240] == 90).all()  # the scene is never drawn over
    assert text_rows(rec.frames[-1]) > text_rows(rec.frames[-1 - 2 * rec.hold_frames]) > text_rows(rec.frames[0])
    assert rec.save(tmp_path / "v.gif").stat().st_size > 0


def test_long_labels_wrap_onto_more_lines_and_the_band_grows(tmp_path: Path) -> None:
    words = [f"w{i:02d}" for i in range(40)]
    lines = wrap(" ".join(words), 308)
    assert len(lines) > 1 and " ".join(lines).split() == words  # every word kept, in order
    assert "".join(wrap("x" * 200, 100)) == "x" * 200  # a word wider than the frame is split, not cut
    rec = VideoRecorder(fps=10, scale=1, hold_s=0.2)
    rec.status("CF4 insert")
    rec.add(SCENE, 0.0)
    outcome = "outcome: " + " ".join(words)
    rec.finish(outcome, False)
    grown, rows = rec.frames[-1], 1 + len(wrap(outcome, 308))  # the label line, then the wrapped outcome
    assert grown.shape[0] == 240 + band_height(rows) > 240 + BAND_PX
    assert grown.shape[0] % 16 == 0
    assert text_rows(grown[:240 + BAND_PX]) < text_rows(grown)  # text below the band's usual three lines
    path = rec.save(tmp_path / "v.mp4")  # frames of two band heights still make one video
    frames = imageio.mimread(path)
    assert {f.shape for f in frames} == {grown.shape}


class OneAction:
    """Opens the right gripper once: a tabletop trial of a few frames."""

    def run(self, robot, log) -> bool:  # noqa: ANN001
        log.status("open_gripper(arm=right)")
        return robot.execute({"action": "open_gripper", "arm": "right"}).reached


def test_a_tabletop_video_ends_on_the_outcome_band(tmp_path: Path) -> None:
    load_builtins()
    METHODS.register("one-action-test", "test: one tabletop action", tags=("system-b",))(
            lambda ctx, settings: OneAction())
    path = tmp_path / "v.mp4"
    try:
        rec = run_trial(TrialSpec(task="pour-single", method="one-action-test", variant="default",
                                  condition="none", seed=0, video=str(path)))
    finally:
        METHODS._entries.pop("one-action-test")  # other tests list the registered methods
    assert rec.error is None and not rec.success and rec.video == str(path)
    frames = imageio.mimread(path)
    scene_h = frames[0].shape[0] - BAND_PX

    def red(frame: np.ndarray) -> int:  # the failed outcome line is drawn in red; mp4 shifts colours a little
        band = frame[scene_h:].astype(int)
        return int(((band[..., 0] > 170) & (band[..., 0] - band[..., 1] > 60)).sum())

    assert red(frames[0]) == 0
    assert red(frames[-1]) > 50
