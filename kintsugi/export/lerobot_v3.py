"""LeRobot's v3.0 dataset layout (LeRobot 0.4 and later), written with pyarrow and imageio-ffmpeg (no lerobot
or torch dependency), for any system's episodes (`recorder.Episode`).

    meta/info.json                               codebase_version v3.0, fps, features, paths, file size caps
    meta/stats.json                              min/max/mean/std/count of every feature over the dataset
    meta/tasks.parquet                           task_index, indexed by the task text (as pandas reads it)
    meta/episodes/chunk-000/file-000.parquet     per episode: tasks, length, dataset_from/to_index, the data and
                                                 video file each lives in with its from/to timestamps, stats/...
    data/chunk-000/file-000.parquet              every frame of every episode, one row each
    videos/observation.images.<camera>/chunk-000/file-000.mp4   every episode's frames, one after the other
    meta/segments.json                           names behind the integer label columns

Columns: `observation.state` (every low-dimensional observation, named `<key>.<component>`), one
`observation.<key>` column per observation entry (joint angles, poses with continuous quaternions, pad or
wrist forces: what the step-level driver reports), `action` (the driver's command), timestamp,
frame_index, episode_index, index, task_index, next.done, next.success, and the labels segment.recovery,
segment.action_index (into meta/segments.json), segment.action_number.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from kintsugi.export.hdf5 import Vocab
from kintsugi.export.lerobot import _pyarrow, _stats, _video_stats, frame_columns, write_video
from kintsugi.export.recorder import ACTION_NAMES, Episode

CODEBASE_VERSION = "v3.0"
CHUNK_SIZE = 1000
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
EPISODES_PATH = "meta/episodes/chunk-000/file-000.parquet"


def _names(ep: Episode, key: str) -> list[str]:
    meta = ep.meta.get("features", {}).get(key, {})
    n = ep.obs[key].shape[1] if ep.obs[key].ndim > 1 else 1
    names = meta.get("names") or [str(i) for i in range(n)]
    return [f"{key}.{c}" for c in names] if n > 1 else [key]


class LeRobotV3Writer:
    """All episodes in one data file and one video file per camera (LeRobot splits at 100 / 200 MB; an
    export of a few hundred trials stays under one file; a larger one is refused rather than mis-written)."""

    def __init__(self, out_dir: Path, source: dict[str, Any]) -> None:
        self.root = Path(out_dir)
        self._pa, self._pq = _pyarrow()
        self._source = source
        self.actions = Vocab()
        self._tasks: dict[str, int] = {}
        self._episodes: list[dict[str, Any]] = []
        self._tables: list[Any] = []
        self._videos: dict[str, Any] = {}
        self._video_s: dict[str, float] = {}
        self._stats: list[dict[str, dict]] = []
        self._frames = 0
        self._fps: float | None = None
        self._features: dict[str, Any] | None = None
        self._keys: list[str] = []

    def add(self, ep: Episode) -> None:
        pa = self._pa
        t = ep.length
        if self._fps is None:
            self._fps = int(ep.fps) if float(ep.fps).is_integer() else ep.fps
            self._keys = list(ep.obs)
            self._features = self._describe(ep)
        i = len(self._episodes)
        task_index = self._tasks.setdefault(ep.instruction, len(self._tasks))
        state = np.hstack([ep.obs[k][:t].reshape(t, -1) for k in self._keys]).astype(np.float32)
        cols = {"observation.state": state, "action": ep.actions.astype(np.float32)}
        cols |= {f"observation.{k}": ep.obs[k][:t].reshape(t, -1).astype(np.float32) for k in self._keys}
        scalars = frame_columns(ep, t, i, self._frames, task_index, self.actions)
        arrays = {k: pa.FixedSizeListArray.from_arrays(pa.array(v.reshape(-1)), v.shape[1]) if v.shape[1] > 1
                  else pa.array(v.reshape(-1)) for k, v in cols.items()}  # shape [1]: a scalar column, as LeRobot reads it
        arrays |= {k: pa.array(v) for k, v in scalars.items()}
        self._tables.append(pa.table(arrays))
        stats = {k: _stats(v) for k, v in (cols | scalars).items()}
        row: dict[str, Any] = {"episode_index": i, "tasks": [ep.instruction], "length": t,
                               "data/chunk_index": 0, "data/file_index": 0,
                               "dataset_from_index": self._frames, "dataset_to_index": self._frames + t}
        for cam, frames in ep.images.items():
            key = f"observation.images.{cam}"
            writer = self._videos.get(key)
            if writer is None:
                writer = self._videos[key] = _open_video(self.root / VIDEO_PATH.format(
                    video_key=key, chunk_index=0, file_index=0), self._fps)
                self._video_s[key] = 0.0
            for f in frames[:t]:
                writer.append_data(f)
            start = self._video_s[key]
            self._video_s[key] = start + t / ep.fps
            row |= {f"videos/{key}/chunk_index": 0, f"videos/{key}/file_index": 0,
                    f"videos/{key}/from_timestamp": start, f"videos/{key}/to_timestamp": self._video_s[key]}
            stats[key] = _video_stats(frames[:t])
        row |= {"meta/episodes/chunk_index": 0, "meta/episodes/file_index": 0,
                "kintsugi_key": ep.key, "recovered": bool(ep.recovery.any()), "success": ep.success}
        for feat, s in stats.items():
            row |= {f"stats/{feat}/{k}": v for k, v in s.items()}
        self._episodes.append(row)
        self._stats.append(stats)
        self._frames += t

    def _describe(self, ep: Episode) -> dict[str, Any]:
        def vec(names: list[str]) -> dict[str, Any]:
            return {"dtype": "float32", "shape": [len(names)], "names": names}
        def one(dtype: str) -> dict[str, Any]:
            return {"dtype": dtype, "shape": [1], "names": None}
        feats: dict[str, Any] = {}
        for cam, frames in ep.images.items():
            h, w, ch = frames.shape[1:]
            feats[f"observation.images.{cam}"] = {
                "dtype": "video", "shape": [h, w, ch], "names": ["height", "width", "channels"],
                "info": {"video.height": h, "video.width": w, "video.codec": "h264", "video.pix_fmt": "yuv420p",
                         "video.is_depth_map": False, "video.fps": self._fps, "video.channels": ch,
                         "has_audio": False}}
        state = [n for k in self._keys for n in _names(ep, k)]
        actions = ep.meta.get("action_names") or list(ACTION_NAMES)
        feats |= {"observation.state": vec(state), "action": vec(list(actions))}
        feats |= {f"observation.{k}": vec(_names(ep, k)) for k in self._keys}
        feats |= {"timestamp": one("float32"), "frame_index": one("int64"), "episode_index": one("int64"),
                  "index": one("int64"), "task_index": one("int64"), "next.done": one("bool"),
                  "next.success": one("bool"), "segment.recovery": one("bool"),
                  "segment.action_index": one("int64"), "segment.action_number": one("int64")}
        return feats

    def close(self) -> Path:
        pa, pq = self._pa, self._pq
        for w in self._videos.values():
            w.close()
        data = self.root / DATA_PATH.format(chunk_index=0, file_index=0)
        data.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.concat_tables(self._tables), data)
        meta = self.root / "meta"
        (meta / "episodes" / "chunk-000").mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.Table.from_pylist(self._episodes), self.root / EPISODES_PATH)
        _write_tasks(pa, pq, meta / "tasks.parquet", self._tasks)
        n = len(self._episodes)
        info = {"codebase_version": CODEBASE_VERSION, "robot_type": f"kintsugi_{self._source.get('system', 'robot')}",
                "total_episodes": n, "total_frames": self._frames, "total_tasks": len(self._tasks),
                "chunks_size": CHUNK_SIZE, "data_files_size_in_mb": 100, "video_files_size_in_mb": 200,
                "fps": self._fps, "splits": {"train": f"0:{n}"}, "data_path": DATA_PATH,
                "video_path": VIDEO_PATH if self._videos else None, "features": self._features}
        (meta / "info.json").write_text(json.dumps(info, indent=4) + "\n")
        (meta / "stats.json").write_text(json.dumps(_aggregate(self._stats), indent=2) + "\n")
        (meta / "segments.json").write_text(json.dumps(
            {"segment.recovery": ["nominal", "recovery"], "segment.action_index": self.actions.names,
             "source": self._source}, indent=2) + "\n")
        return self.root

    def abort(self) -> None:
        for w in self._videos.values():
            w.close()


def _open_video(path: Path, fps: float) -> Any:
    import imageio.v2 as imageio

    path.parent.mkdir(parents=True, exist_ok=True)
    return imageio.get_writer(path, fps=fps, codec="libx264", pixelformat="yuv420p", macro_block_size=2,
                              quality=None, ffmpeg_params=["-g", "2", "-crf", "23"], ffmpeg_log_level="error")


def _write_tasks(pa: Any, pq: Any, path: Path, tasks: dict[str, int]) -> None:
    """task_index with the task text as the pandas index (what LeRobot's `load_tasks` reads back)."""
    table = pa.table({"task_index": pa.array(list(tasks.values()), pa.int64()), "task": pa.array(list(tasks))})
    pandas_meta = {"index_columns": ["task"], "column_indexes": [], "pandas_version": "2.2.0", "creator": {},
                   "columns": [{"name": "task_index", "field_name": "task_index", "pandas_type": "int64",
                                "numpy_type": "int64", "metadata": None},
                               {"name": "task", "field_name": "task", "pandas_type": "unicode",
                                "numpy_type": "object", "metadata": None}]}
    pq.write_table(table.replace_schema_metadata({"pandas": json.dumps(pandas_meta)}), path)


def _aggregate(per_episode: list[dict[str, dict]]) -> dict[str, dict]:
    """Dataset statistics from the episodes' (count-weighted mean and pooled variance, as LeRobot merges)."""
    out: dict[str, dict] = {}
    for feat in per_episode[0]:
        parts = [s[feat] for s in per_episode]
        n = np.array([p["count"][0] for p in parts], dtype=np.float64)
        mean = np.array([p["mean"] for p in parts], dtype=np.float64)
        std = np.array([p["std"] for p in parts], dtype=np.float64)
        shape = (len(n),) + (1,) * (mean.ndim - 1)
        w = n.reshape(shape) / n.sum()
        m = (w * mean).sum(0)
        var = (w * (std ** 2 + (mean - m) ** 2)).sum(0)
        out[feat] = {"min": np.min([p["min"] for p in parts], 0).tolist(),
                     "max": np.max([p["max"] for p in parts], 0).tolist(),
                     "mean": m.tolist(), "std": np.sqrt(var).tolist(), "count": [int(n.sum())]}
    return out
