"""Draw docs/img/systems.png: one frame of each system's video, side by side (A peg, B pour, C flip).

    .venv/bin/python docs/tools/systems_picture.py
"""

from __future__ import annotations

import tempfile
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "img" / "systems.png"
TRIALS = (("peg-insertion", "recovery", "all", 7, 0.75), ("pour-single", "agentchord", "none", 0, 0.45),
          ("flip-box", "expert-fsm", "all", 0, 0.6))
"""(task, method, condition, seed, where in the video the frame is taken, 0..1)."""


def main() -> None:
    import kintsugi
    import imageio.v3 as iio
    import numpy as np

    frames = []
    with tempfile.TemporaryDirectory() as tmp:
        for task, method, condition, seed, at in TRIALS:
            video = Path(tmp) / f"{task}.mp4"
            kintsugi.run(task, method=method, condition=condition, seed=seed, video=video)
            clip = iio.imread(video)
            frames.append(clip[int(at * (len(clip) - 1))])
    height = min(f.shape[0] for f in frames)
    scaled = []
    for f in frames:  # same height, nearest-neighbour rows/columns
        rows = np.linspace(0, f.shape[0] - 1, height).astype(int)
        cols = np.linspace(0, f.shape[1] - 1, int(f.shape[1] * height / f.shape[0])).astype(int)
        scaled.append(f[rows][:, cols])
    gap = np.full((height, 8, 3), 255, dtype=np.uint8)
    row = np.concatenate([x for f in scaled for x in (f, gap)][:-1], axis=1)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(OUT, row)
    print(f"wrote {OUT} {row.shape[1]}x{row.shape[0]}")


if __name__ == "__main__":
    main()
