"""Trial videos from the scene camera, with the current contact formation and verdict overlaid."""

from __future__ import annotations

from pathlib import Path

import cv2
import imageio.v2 as imageio
import numpy as np

from kintsugi.errors import KintsugiError


class VideoRecorder:
    """Collects frames every `1/fps` seconds of sim time; `status` text is drawn on each."""

    def __init__(self, fps: float = 25.0, scale: int = 2) -> None:
        self.fps = fps
        self.scale = scale
        self.frames: list[np.ndarray] = []
        self.label = ""
        self.verdict = ""
        self._next_t = 0.0

    def on_tick(self, world) -> None:  # noqa: ANN001 - any world with .data.time and .render()
        t = float(world.data.time)
        if t + 1e-9 < self._next_t:
            return
        self._next_t = t + 1.0 / self.fps
        self.add(world.render(), t)

    def add(self, image: np.ndarray, t: float) -> None:
        frame = cv2.resize(image, None, fx=self.scale, fy=self.scale, interpolation=cv2.INTER_NEAREST)
        lines = [f"t={t:5.2f}s  {self.label}"] + ([self.verdict] if self.verdict else [])
        for i, text in enumerate(lines):
            y = 18 + 18 * i
            cv2.putText(frame, text[:70], (6, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
            colour = (255, 255, 255)
            if i == 1:
                colour = (120, 255, 120) if "SUCCESS" in text else (255, 140, 140)
            cv2.putText(frame, text[:70], (6, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, colour, 1, cv2.LINE_AA)
        self.frames.append(frame)

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        if not self.frames:
            raise KintsugiError("no frames were recorded; did the trial run any skill?")
        path.parent.mkdir(parents=True, exist_ok=True)
        suffix = path.suffix.lower()
        if suffix == ".mp4":
            imageio.mimsave(path, self.frames, fps=self.fps, macro_block_size=8)
        elif suffix == ".gif":
            imageio.mimsave(path, self.frames, duration=1.0 / self.fps, loop=0)
        else:
            raise KintsugiError(f"video path {path} must end in .mp4 or .gif")
        return path
