"""LeRobot's v2.1 dataset layout, written with pyarrow and imageio-ffmpeg (no lerobot / torch dependency).

    meta/info.json            codebase_version v2.1, fps, features (dtype, shape, names; video info)
    meta/episodes.jsonl       {"episode_index", "tasks", "length"} (+ kintsugi_key, recovered, success)
    meta/tasks.jsonl          {"task_index", "task"}: the task instructions
    meta/episodes_stats.jsonl per-episode min/max/mean/std/count of every feature (video: per channel in [0, 1])
    meta/segments.json        names behind the integer label columns (edge, atomic action)
    data/chunk-000/episode_000000.parquet
    videos/chunk-000/observation.images.<camera>/episode_000000.mp4   (h264, yuv420p, every frame decodable)

Columns: observation.state (per arm: 6 joint angles rad, gripper opening m), observation.eef_pose (per arm:
position m, quaternion xyzw), action (per arm: 6 joint targets rad, gripper closed 0/1), timestamp,
frame_index, episode_index, index, task_index, next.done, next.success, and the segment labels
segment.recovery (bool), segment.edge_index, segment.action_index (into meta/segments.json), segment.action_number.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from kintsugi.export.hdf5 import Vocab
from kintsugi.export.recorder import ACTION_NAMES, Episode
from kintsugi.worlds.tabletop.arm_model import JOINTS
from kintsugi.worlds.tabletop.config import ARMS

CODEBASE_VERSION = "v2.1"
CHUNK_SIZE = 1000
DATA_PATH = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
VIDEO_PATH = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
STATE_NAMES = tuple(n for arm in ARMS for n in (*(f"{arm}_{j}" for j in JOINTS), f"{arm}_gripper_opening"))
POSE_NAMES = tuple(f"{arm}_{c}" for arm in ARMS for c in ("x", "y", "z", "qx", "qy", "qz", "qw"))


def _pyarrow() -> Any:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        from kintsugi.core.errors import ConfigError

        raise ConfigError("--format lerobot needs pyarrow: pip install 'kintsugi[export]'") from None
    return pa, pq


def state_of(ep: Episode) -> np.ndarray:
    return np.hstack([ep.obs[f"{arm}_{k}"] for arm in ARMS for k in ("joint_pos", "gripper_opening")])


def pose_of(ep: Episode) -> np.ndarray:
    return np.hstack([ep.obs[f"{arm}_{k}"] for arm in ARMS for k in ("eef_pos", "eef_quat")])


def _stats(x: np.ndarray) -> dict[str, list]:
    x = np.asarray(x, dtype=np.float64).reshape(len(x), -1)
    return {"min": x.min(0).tolist(), "max": x.max(0).tolist(), "mean": x.mean(0).tolist(),
            "std": x.std(0).tolist(), "count": [len(x)]}


def _video_stats(frames: np.ndarray) -> dict[str, list]:
    """Per channel, in [0, 1], shaped (3, 1, 1) as LeRobot keeps image stats; over every 4th pixel row and
    column (the statistics of a smooth render barely move, the cost drops 16-fold)."""
    x = frames[:, ::4, ::4].reshape(-1, frames.shape[-1]).astype(np.float32) / 255.0
    def shaped(v: np.ndarray) -> list:
        return [[[float(c)]] for c in v]
    return {"min": shaped(x.min(0)), "max": shaped(x.max(0)), "mean": shaped(x.mean(0)),
            "std": shaped(x.std(0)), "count": [len(frames)]}


def write_video(path: Path, frames: np.ndarray, fps: float) -> None:
    import imageio.v2 as imageio

    path.parent.mkdir(parents=True, exist_ok=True)
    writer = imageio.get_writer(path, fps=fps, codec="libx264", pixelformat="yuv420p", macro_block_size=16,
                                quality=None, ffmpeg_params=["-g", "2", "-crf", "23"], ffmpeg_log_level="error")
    try:
        for f in frames:
            writer.append_data(f)
    finally:
        writer.close()


def frame_columns(ep: Episode, t: int, episode: int, first: int, task_index: int, actions: Vocab) -> dict[str, Any]:
    """The per-frame columns both LeRobot layouts share: time and indices, the episode's end and success, and
    which action (and whether a recovery) each frame belongs to."""
    return {
        "timestamp": (np.arange(t) / ep.fps).astype(np.float32),
        "frame_index": np.arange(t, dtype=np.int64),
        "episode_index": np.full(t, episode, dtype=np.int64),
        "index": np.arange(first, first + t, dtype=np.int64),
        "task_index": np.full(t, task_index, dtype=np.int64),
        "next.done": np.arange(t) == t - 1,
        "next.success": (np.arange(t) == t - 1) & ep.success,
        "segment.recovery": ep.recovery,
        "segment.action_index": actions.ids(ep.action),
        "segment.action_number": ep.action_number,
    }


class LeRobotWriter:
    def __init__(self, out_dir: Path, source: dict[str, Any]) -> None:
        self.root = Path(out_dir)
        self._pa, self._pq = _pyarrow()
        self._source = source
        self.edges, self.actions = Vocab(), Vocab()
        self._tasks: dict[str, int] = {}
        self._episodes: list[dict[str, Any]] = []
        self._stats: list[dict[str, Any]] = []
        self._frames = 0
        self._fps: float | None = None
        self._cameras: dict[str, tuple[int, ...]] = {}

    def add(self, ep: Episode) -> None:
        pa, pq = self._pa, self._pq
        if self._fps is None:
            self._fps = int(ep.fps) if float(ep.fps).is_integer() else ep.fps  # LeRobot datasets state int fps
            self._cameras = {c: f.shape[1:] for c, f in ep.images.items()}
        i, t = len(self._episodes), ep.length
        task_index = self._tasks.setdefault(ep.instruction, len(self._tasks))
        chunk = i // CHUNK_SIZE
        cols = {
            "observation.state": state_of(ep)[:t].astype(np.float32),
            "observation.eef_pose": pose_of(ep)[:t].astype(np.float32),
            "action": ep.actions.astype(np.float32),
        }
        scalars = frame_columns(ep, t, i, self._frames, task_index, self.actions)
        scalars["segment.edge_index"] = self.edges.ids(ep.edge)
        arrays = {k: pa.FixedSizeListArray.from_arrays(pa.array(v.reshape(-1)), v.shape[1]) for k, v in cols.items()}
        arrays |= {k: pa.array(v) for k, v in scalars.items()}
        path = self.root / DATA_PATH.format(episode_chunk=chunk, episode_index=i)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.table(arrays), path)
        stats = {k: _stats(v) for k, v in (cols | scalars).items()}
        for cam, frames in ep.images.items():
            key = f"observation.images.{cam}"
            write_video(self.root / VIDEO_PATH.format(episode_chunk=chunk, video_key=key, episode_index=i),
                        frames[:t], ep.fps)
            stats[key] = _video_stats(frames[:t])
        self._stats.append({"episode_index": i, "stats": stats})
        self._episodes.append({"episode_index": i, "tasks": [ep.instruction], "length": t,
                               "kintsugi_key": ep.key, "recovered": bool(ep.recovery.any()), "success": ep.success})
        self._frames += t

    def _features(self) -> dict[str, Any]:
        def vec(names: tuple[str, ...]) -> dict[str, Any]:
            return {"dtype": "float32", "shape": [len(names)], "names": list(names)}
        def one(dtype: str) -> dict[str, Any]:
            return {"dtype": dtype, "shape": [1], "names": None}
        feats: dict[str, Any] = {}
        for cam, (h, w, ch) in self._cameras.items():
            feats[f"observation.images.{cam}"] = {
                "dtype": "video", "shape": [h, w, ch], "names": ["height", "width", "channel"],
                "info": {"video.fps": self._fps, "video.height": h, "video.width": w, "video.channels": ch,
                         "video.codec": "h264", "video.pix_fmt": "yuv420p", "video.is_depth_map": False,
                         "has_audio": False}}
        feats |= {"observation.state": vec(STATE_NAMES), "observation.eef_pose": vec(POSE_NAMES),
                  "action": vec(ACTION_NAMES), "timestamp": one("float32"), "frame_index": one("int64"),
                  "episode_index": one("int64"), "index": one("int64"), "task_index": one("int64"),
                  "next.done": one("bool"), "next.success": one("bool"), "segment.recovery": one("bool"),
                  "segment.edge_index": one("int64"), "segment.action_index": one("int64"),
                  "segment.action_number": one("int64")}
        return feats

    def close(self) -> Path:
        meta = self.root / "meta"
        meta.mkdir(parents=True, exist_ok=True)
        n = len(self._episodes)
        info = {
            "codebase_version": CODEBASE_VERSION, "robot_type": "kintsugi_bimanual_6dof",
            "total_episodes": n, "total_frames": self._frames, "total_tasks": len(self._tasks),
            "total_videos": n * len(self._cameras), "total_chunks": (n - 1) // CHUNK_SIZE + 1 if n else 0,
            "chunks_size": CHUNK_SIZE, "fps": self._fps, "splits": {"train": f"0:{n}"},
            "data_path": DATA_PATH, "video_path": VIDEO_PATH if self._cameras else None,
            "features": self._features(),
        }
        (meta / "info.json").write_text(json.dumps(info, indent=4) + "\n")
        _jsonl(meta / "episodes.jsonl", self._episodes)
        _jsonl(meta / "tasks.jsonl", [{"task_index": i, "task": t} for t, i in self._tasks.items()])
        _jsonl(meta / "episodes_stats.jsonl", self._stats)
        (meta / "segments.json").write_text(json.dumps(
            {"segment.recovery": ["nominal", "recovery"], "segment.edge_index": self.edges.names,
             "segment.action_index": self.actions.names, "source": self._source}, indent=2) + "\n")
        return self.root

    def abort(self) -> None:
        return None


def _jsonl(path: Path, rows: list[dict[str, Any]]) -> None:
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
