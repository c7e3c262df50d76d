"""Trial videos from the scene camera, with the current contact formation, the verdicts and the outcome.

The text goes in a black band under the scene, never over it, so it cannot hide the
gripper or the peg; a label wider than the frame wraps onto more lines and the band grows. The final outcome (ground truth G and the method's verdict F) is
added by `finish` only after the trial has been scored: during the run the recorder
sees nothing but rendered frames and the method's own status.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import imageio.v2 as imageio
import numpy as np

from kintsugi.core.errors import KintsugiError
from kintsugi.core.outputs import check_output_file

VIDEO_SUFFIXES = (".mp4", ".gif")
LINE_PX = 18
BAND_PX = 64  # three lines; 480 + 64 keeps the default frame a multiple of 16 for the encoder
MARGIN_PX = 6
FONT, FONT_SCALE = cv2.FONT_HERSHEY_SIMPLEX, 0.5
WHITE, GREEN, RED = (255, 255, 255), (120, 255, 120), (255, 140, 140)


def check_video_path(path: str | Path) -> Path:
    """Raise ConfigError unless `path` is a writable .mp4 or .gif (checked before the trial runs)."""
    return check_output_file(Path(path), "video", VIDEO_SUFFIXES)


class VideoRecorder:
    """Collects frames every `1/fps` seconds of sim time, each with the status band below it."""

    def __init__(self, fps: float = 25.0, scale: int = 2, hold_s: float = 0.6) -> None:
        self.fps = fps
        self.scale = scale
        self.hold_frames = max(1, round(hold_s * fps))
        self.frames: list[np.ndarray] = []
        self.label = ""
        self.verdict = ""
        self._last: tuple[np.ndarray, float] | None = None
        self._next_t = 0.0

    def on_tick(self, world) -> None:  # noqa: ANN001 - any world with .data.time and .render()
        t = float(world.data.time)
        if t + 1e-9 < self._next_t:
            return
        self._next_t = t + 1.0 / self.fps
        self.add(world.render(), t)

    def status(self, label: str, verdict: str | None = None) -> None:
        """The method's status; a new verdict is held on the last frame so it is seen even when
        nothing moves after it (the insert verdict ends the trial)."""
        self.label = label
        if verdict is not None and verdict != self.verdict:
            self.verdict = verdict
            if self._last is not None:
                self._hold([(self._first_line(self._last[1]), WHITE), self._verdict_line()])

    def finish(self, outcome: str, success: bool) -> None:
        """Append the scored outcome, held on the last frame; call only after the trial is scored."""
        if self._last is None:
            return
        lines = [(self._first_line(self._last[1]), WHITE), self._verdict_line(), (outcome, GREEN if success else RED)]
        self._hold(lines, frames=self.hold_frames * 2)

    def add(self, image: np.ndarray, t: float) -> None:
        self._last = (image, t)
        self.frames.append(self._compose(image, [(self._first_line(t), WHITE), self._verdict_line()]))

    def _first_line(self, t: float) -> str:
        return f"t={t:5.2f}s  {self.label}"

    def _verdict_line(self) -> tuple[str, tuple[int, int, int]]:
        return self.verdict, (GREEN if "SUCCESS" in self.verdict else RED)

    def _hold(self, lines: list[tuple[str, tuple[int, int, int]]], frames: int | None = None) -> None:
        assert self._last is not None
        frame = self._compose(self._last[0], lines)
        self.frames.extend(frame for _ in range(frames or self.hold_frames))

    def _compose(self, image: np.ndarray, lines: list[tuple[str, tuple[int, int, int]]]) -> np.ndarray:
        scene = cv2.resize(image, None, fx=self.scale, fy=self.scale, interpolation=cv2.INTER_NEAREST)
        rows = [(part, colour) for text, colour in lines if text for part in wrap(text, scene.shape[1] - 2 * MARGIN_PX)]
        band = np.zeros((band_height(len(rows)), scene.shape[1], 3), dtype=scene.dtype)
        for i, (text, colour) in enumerate(rows):
            cv2.putText(band, text, (MARGIN_PX, 16 + LINE_PX * i), FONT, FONT_SCALE, colour, 1, cv2.LINE_AA)
        return np.vstack([scene, band])

    def save(self, path: str | Path) -> Path:
        path = check_video_path(path)
        if not self.frames:
            raise KintsugiError("no frames were recorded; did the trial run any skill?")
        path.parent.mkdir(parents=True, exist_ok=True)
        frames = same_height(self.frames)
        if path.suffix.lower() == ".mp4":
            imageio.mimsave(path, frames, fps=self.fps, macro_block_size=8)
        else:
            imageio.mimsave(path, frames, duration=1.0 / self.fps, loop=0)
        return path


def wrap(text: str, width_px: int) -> list[str]:
    """`text` in lines that fit `width_px` in the band's font, broken between words (inside a word
    only when the word alone is too wide): a long label takes more lines, never loses its end."""
    def fits(line: str) -> bool:
        return cv2.getTextSize(line, FONT, FONT_SCALE, 1)[0][0] <= width_px

    out: list[str] = []
    line = ""
    for word in text.split():
        candidate = f"{line} {word}" if line else word
        if fits(candidate):
            line = candidate
            continue
        if line:
            out.append(line)
        while not fits(word) and len(word) > 1:  # a word wider than the frame: cut it where it must
            cut = next((i for i in range(len(word) - 1, 0, -1) if fits(word[:i])), 1)
            out.append(word[:cut])
            word = word[cut:]
        line = word
    return out + [line] if line else out


def band_height(rows: int) -> int:
    """The band under the scene: three lines at least, more for wrapped text, a multiple of 16 px."""
    need = 16 + LINE_PX * max(0, rows - 1) + 8
    return max(BAND_PX, -(-need // 16) * 16)


def same_height(frames: list[np.ndarray]) -> list[np.ndarray]:
    """Frames padded (black, at the bottom of the band) to the tallest one: a video has one frame size,
    and a wrapped outcome may have grown the band of the last frames."""
    tallest = max(f.shape[0] for f in frames)
    return [f if f.shape[0] == tallest else np.pad(f, ((0, tallest - f.shape[0]), (0, 0), (0, 0))) for f in frames]
