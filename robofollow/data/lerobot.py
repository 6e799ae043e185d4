"""What LeRobot v2.1 and v3.0 datasets share: the feature schema, the per-frame table, the
episode list (one per demonstration and instruction) and the per-episode statistics."""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from robofollow.data.sinks import image_key
from robofollow.data.stats import array_stats, as_image_stats
from robofollow.data.units import ROBOT_TYPE, RecordError
from robofollow.errors import error_text
from robofollow.sim import robot
from robofollow.sim.cameras import CAMERA_NAMES
from robofollow.sim.objects import FIELDS, FLAT, MAX_OBJECTS
from robofollow.sim.simulation import CONTROL_HZ
from robofollow.sim.video import CODEC_NAME, PIXEL_FORMAT
from robofollow.trajectory import MAX_TRAJECTORY_BYTES, npz_problem

FPS = CONTROL_HZ  # frames are recorded at the control rate: no resampling
CHUNKS_SIZE = 1000  # files per chunk folder
VIDEO_KEYS = tuple(image_key(camera) for camera in CAMERA_NAMES)
INDEX_COLUMNS = ("frame_index", "episode_index", "index", "task_index")
EXTRA_EPISODE_FIELDS = ("label", "scene", "layout", "seed", "spec_digest")
ENVIRONMENT_STATE = "observation.environment_state"  # LeRobot's name: the objects observation
OBJECT_NAMES = tuple(f"object_{row}.{field}" for row in range(MAX_OBJECTS) for field in FIELDS)
ARRAYS = ("state", "environment_state", "action")  # a unit's arrays.npz (units.dataset_arrays)
MAX_ARRAYS_BYTES = MAX_TRAJECTORY_BYTES  # arrays.npz: a part of its recording's trajectory


@dataclass(frozen=True)
class Episode:
    """One dataset episode: a demonstration with one of its instructions."""
    index: int
    demo: dict  # the unit's demo.json record
    unit: Path
    task: str
    task_index: int

    @property
    def length(self) -> int:
        return self.demo["length"]

    def metadata(self) -> dict:
        return {key: self.demo[key] for key in EXTRA_EPISODE_FIELDS}


def episodes(demos: list[tuple[dict, Path]]) -> tuple[list[Episode], list[str]]:
    """Episodes in demonstration order (each instruction of a demo in turn) and the task
    strings in order of first appearance."""
    tasks: dict[str, int] = {}
    result = []
    for demo, unit in demos:
        for instruction in demo["instructions"]:
            task_index = tasks.setdefault(instruction, len(tasks))
            result.append(Episode(len(result), demo, unit, instruction, task_index))
    return result, list(tasks)


def features(width: int, height: int) -> dict:
    video_info = {"video.height": height, "video.width": width,
                  "video.codec": CODEC_NAME,
                  "video.pix_fmt": PIXEL_FORMAT, "video.is_depth_map": False, "video.fps": FPS,
                  "video.channels": 3, "has_audio": False}
    result = {key: {"dtype": "video", "shape": [height, width, 3],
                    "names": ["height", "width", "channels"], "info": video_info}
              for key in VIDEO_KEYS}
    for key in ("observation.state", "action"):
        result[key] = {"dtype": "float32", "shape": [len(robot.JOINT_NAMES)],
                       "names": list(robot.JOINT_NAMES)}
    result[ENVIRONMENT_STATE] = {"dtype": "float32", "shape": [FLAT],
                                 "names": list(OBJECT_NAMES)}
    result["timestamp"] = {"dtype": "float32", "shape": [1], "names": None}
    for key in INDEX_COLUMNS:
        result[key] = {"dtype": "int64", "shape": [1], "names": None}
    return result


def info(version: str, width: int, height: int, episode_list: list[Episode], tasks: list[str],
         paths: dict) -> dict:
    """meta/info.json; `paths` adds the version's path templates and chunking fields."""
    return {"codebase_version": version, "robot_type": ROBOT_TYPE,
            "total_episodes": len(episode_list),
            "total_frames": sum(e.length for e in episode_list), "total_tasks": len(tasks),
            **paths, "fps": FPS, "splits": {"train": f"0:{len(episode_list)}"},
            "features": features(width, height)}


def load_arrays(unit: Path) -> dict[str, np.ndarray]:
    """A unit's arrays.npz: ARRAYS, at most MAX_ARRAYS_BYTES of them; else RecordError naming
    the file."""
    path = unit / "arrays.npz"
    problem = npz_problem(path, MAX_ARRAYS_BYTES)
    if problem:
        raise RecordError(f"{path}: {problem}")
    try:
        with np.load(path, allow_pickle=False) as data:
            missing = [key for key in ARRAYS if key not in data.files]
            if missing:
                raise RecordError(f"{path}: no {', '.join(missing)} among its arrays")
            return {key: data[key] for key in ARRAYS}
    except (OSError, ValueError, MemoryError, zipfile.BadZipFile) as error:
        raise RecordError(f"{path}: cannot read a unit's arrays ({error_text(error)})"
                          ) from None


def frame_table(episode: Episode, arrays: dict[str, np.ndarray], start: int) -> pa.Table:
    """One row per frame; `start` is the global index of the episode's first frame."""
    n, width = episode.length, len(robot.JOINT_NAMES)
    frames = np.arange(n, dtype=np.int64)
    columns = {
        "observation.state": pa.FixedSizeListArray.from_arrays(
            pa.array(arrays["state"].reshape(-1), pa.float32()), width),
        ENVIRONMENT_STATE: pa.FixedSizeListArray.from_arrays(
            pa.array(arrays["environment_state"].reshape(-1), pa.float32()), FLAT),
        "action": pa.FixedSizeListArray.from_arrays(
            pa.array(arrays["action"].reshape(-1), pa.float32()), width),
        "timestamp": pa.array((frames / FPS).astype(np.float32)),
        "frame_index": pa.array(frames),
        "episode_index": pa.array(np.full(n, episode.index, dtype=np.int64)),
        "index": pa.array(start + frames),
        "task_index": pa.array(np.full(n, episode.task_index, dtype=np.int64)),
    }
    return pa.table(columns)


def vectors(column: pa.ChunkedArray) -> np.ndarray:
    """A fixed-size-list column (state, action) as an [N, D] array."""
    column = column.combine_chunks()
    return column.flatten().to_numpy().reshape(len(column), -1)


def episode_stats(episode: Episode, table: pa.Table) -> dict[str, dict]:
    """Statistics of every feature of one episode (images from the unit's running stats)."""
    stats = {}
    for name in table.column_names:
        column = table.column(name)
        if pa.types.is_fixed_size_list(column.type):
            values = vectors(column)
        else:
            values = column.to_numpy()
        stats[name] = array_stats(values)
    for key in VIDEO_KEYS:
        stats[key] = as_image_stats(episode.demo["image_stats"][key])
    return stats
