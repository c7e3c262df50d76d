"""Loads a kintsugi LeRobot v3.0 export with LeRobot's own `LeRobotDataset` (offline, from a local root) and
prints what it found as JSON. Run by `tests/export/test_lerobot_load.py` inside the optional LeRobot
environment (`make lerobot-check`); not collected by pytest in the default one."""

from __future__ import annotations

import json
import sys


def main(root: str) -> None:
    from lerobot.datasets.lerobot_dataset import CODEBASE_VERSION, LeRobotDataset

    ds = LeRobotDataset("kintsugi/export", root=root, video_backend="torchcodec")
    first, last = ds[0], ds[len(ds) - 1]
    shapes = {k: list(v.shape) for k, v in first.items() if hasattr(v, "shape")}
    print(json.dumps({"codebase_version": CODEBASE_VERSION, "frames": ds.num_frames, "episodes": ds.num_episodes,
                      "features": sorted(ds.features), "shapes": shapes, "task": first["task"],
                      "last_episode": int(last["episode_index"]), "video_keys": ds.meta.video_keys,
                      "video_mean": {k: float(first[k].float().mean()) for k in ds.meta.video_keys}}))


if __name__ == "__main__":
    main(sys.argv[1])
