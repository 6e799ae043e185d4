"""Reading a RoboFollow LeRobot dataset (v2.1 or v3.0, as `robofollow generate` writes it) for
training: every frame's joint state and action, each episode's instruction and task label, the
chosen cameras' frames, decoded with PyAV and shrunk by an integer factor (area average), and,
where asked, every frame's objects observation (`observation.environment_state`).

Decoded frames are cached as .npy files keyed by the dataset's identity, so a second training
run on the same dataset (or a resumed one) skips decoding.
"""

from __future__ import annotations

import hashlib
import json
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from itertools import islice
from pathlib import Path

import av
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from robofollow.data import lerobot_v21, lerobot_v30
from robofollow.data.check_parts import (
    MAX_JSON_BYTES,
    MAX_JSONL_BYTES,
    MAX_PARQUET_BYTES,
    MAX_VIDEO_BYTES,
)
from robofollow.data.lerobot import ENVIRONMENT_STATE, vectors
from robofollow.data.sinks import image_key
from robofollow.errors import RoboFollowError
from robofollow.files import (
    file_problem,
    json_lines,
    number_problem,
    read_file_at_most,
    read_json_file,
    shown,
)
from robofollow.sim.objects import SHAPE as OBJECTS_SHAPE


class DatasetError(RoboFollowError):
    """A training dataset that cannot be read."""


@dataclass(frozen=True)
class Demonstrations:
    """A dataset's frames in episode order; episode e owns frames starts[e]:starts[e]+lengths[e]."""
    states: np.ndarray  # [N, 14] float32
    actions: np.ndarray  # [N, 14] float32
    starts: np.ndarray  # [E] int64
    lengths: np.ndarray  # [E] int64
    instructions: list[str]  # per episode
    labels: list[str]  # per episode: the training task
    images: dict[str, np.ndarray]  # camera -> [N, H, W, 3] uint8
    objects: np.ndarray | None = None  # [N, rows, fields] float32, where read

    @property
    def episodes(self) -> int:
        return len(self.lengths)


def downsample(images: np.ndarray, factor: int) -> np.ndarray:
    """[..., H, W, 3] uint8 images shrunk by `factor` in each direction (area average,
    rounded); the same function prepares training frames and a policy's observations."""
    if factor == 1:
        return np.ascontiguousarray(images, dtype=np.uint8)
    height, width = images.shape[-3] // factor, images.shape[-2] // factor
    total = np.zeros(images.shape[:-3] + (height, width, images.shape[-1]), np.uint16)
    for row in range(factor):
        for column in range(factor):
            total += images[..., row::factor, column::factor, :][..., :height, :width, :]
    return ((total + factor * factor // 2) // (factor * factor)).astype(np.uint8)


def read_demonstrations(root: Path, cameras: tuple[str, ...], factor: int,
                        progress=None, cache: Path | None = None,
                        objects: bool = False) -> Demonstrations:
    """The dataset under `root`; `progress(n)` is called as episodes' frames are decoded;
    `objects`: read the objects observation too."""
    info = _info(root / "meta" / "info.json")
    episodes = (_v21_episodes(root) if info["codebase_version"] == lerobot_v21.VERSION
                else _v30_episodes(root))
    frames = _frames(root, objects)
    starts = np.cumsum([0] + [e["length"] for e in episodes[:-1]]).astype(np.int64)
    lengths = np.array([e["length"] for e in episodes], np.int64)
    if len(frames["index"]) != lengths.sum():
        raise DatasetError(f"{root}: {len(frames['index'])} frames, the episodes list "
                           f"{lengths.sum()}")
    images = {camera: _camera(root, info, episodes, camera, factor, progress, cache)
              for camera in cameras}
    return Demonstrations(frames["state"], frames["action"], starts, lengths,
                          [e["tasks"][0] for e in episodes],
                          [e.get("label", e["tasks"][0]) for e in episodes], images,
                          frames.get("objects"))


# the keys each version's video_path template is formatted with (the values try it)
VIDEO_PATH_KEYS = {lerobot_v21.VERSION: {"episode_chunk": 0, "video_key": "", "episode_index": 0},
                   lerobot_v30.VERSION: {"video_key": "", "chunk_index": 0, "file_index": 0}}


def _info(path: Path) -> dict:
    """meta/info.json: an object whose codebase_version, fps, features, video_path and (v2.1)
    chunks_size training can use; the other fields are not read."""
    info, problem = read_json_file(path, MAX_JSON_BYTES)
    problem = problem or _info_problem(info)
    if problem:
        raise DatasetError(f"{path}: not a readable dataset file ({problem})")
    return info


def _info_problem(info) -> str | None:
    if not isinstance(info, dict):
        return f"{shown(info)} is not a JSON object"
    version = info.get("codebase_version")
    if not isinstance(version, str) or version not in VIDEO_PATH_KEYS:
        return f"codebase_version is {shown(version)}, not v2.1 or v3.0"
    fps = number_problem(info.get("fps"), 1)
    if fps:
        return f"fps {fps}"
    if not isinstance(info.get("features", {}), dict):
        return f"features is {shown(info['features'])}, not an object"
    if version == lerobot_v21.VERSION and not _whole(info.get("chunks_size"), 1):
        return f"chunks_size is {shown(info.get('chunks_size'))}, not a whole number from 1"
    try:
        info["video_path"].format(**VIDEO_PATH_KEYS[version])
    except (AttributeError, KeyError, IndexError, TypeError, ValueError):
        return (f"video_path is {shown(info.get('video_path'))}, not a path template of "
                f"{', '.join(VIDEO_PATH_KEYS[version])}")
    return None


def _whole(value, low: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= low


def _episode_problem(record) -> str | None:
    """What is wrong with an episode's record (episode_index, length, tasks, an optional
    label: the fields training reads), or None."""
    if not isinstance(record, dict):
        return f"{shown(record)} is not an object"
    for key in ("episode_index", "length"):
        if not _whole(record.get(key), 0):
            return f"{key} is {shown(record.get(key))}, not a whole number from 0"
    tasks = record.get("tasks")
    if not (isinstance(tasks, list) and tasks and all(isinstance(t, str) for t in tasks)):
        return f"tasks is {shown(tasks)}, not a list of instructions"
    if not isinstance(record.get("label") or "", str):
        return f"label is {shown(record['label'])}, not a string"
    return None


def _v21_episodes(root: Path) -> list[dict]:
    path = root / "meta" / "episodes.jsonl"
    data, problem = read_file_at_most(path, MAX_JSONL_BYTES)
    if problem:
        raise DatasetError(f"{path}: {problem}")
    episodes = []
    for line in json_lines(data):
        if line.problem:
            raise DatasetError(f"{path}:{line.number}:{line.column}: {line.problem}")
        problem = _episode_problem(line.value)
        if problem:
            raise DatasetError(f"{path}:{line.number}: {problem}")
        episodes.append(line.value)
    return sorted(episodes, key=lambda e: e["episode_index"])


def _v30_episodes(root: Path) -> list[dict]:
    folder = root / "meta" / "episodes"
    files = sorted(folder.rglob("*.parquet"))
    if not files:
        raise DatasetError(f"{folder}: no parquet files")
    try:
        rows = pa.concat_tables([_table(f) for f in files]).to_pylist()
    except (OSError, pa.ArrowException) as error:
        raise DatasetError(f"{folder}: {error}") from None
    for number, row in enumerate(rows):
        problem = _episode_problem(row)
        if problem:
            raise DatasetError(f"{folder}: row {number}: {problem}")
    return sorted(rows, key=lambda e: e["episode_index"])


def _table(path: Path, columns: list[str] | None = None) -> pa.Table:
    """A parquet file's table; DatasetError for one that is not a regular file of at most
    MAX_PARQUET_BYTES."""
    problem = file_problem(path, MAX_PARQUET_BYTES)
    if problem:
        raise DatasetError(f"{path}: {problem}")
    return pq.read_table(path, columns=columns)


def _frames(root: Path, objects: bool) -> dict[str, np.ndarray]:
    files = sorted((root / "data").rglob("*.parquet"))
    if not files:
        raise DatasetError(f"{root}/data: no parquet files")
    columns = ["observation.state", "action", "index"] + ([ENVIRONMENT_STATE] if objects else [])
    try:
        table = pa.concat_tables(_table(f, columns) for f in files)
    except (OSError, pa.ArrowException, KeyError) as error:
        lacks = objects and ENVIRONMENT_STATE in str(error)
        raise DatasetError(f"{root}/data: " + (
            f"no {ENVIRONMENT_STATE} (the objects observation; datasets generated before it "
            "lack it: generate it again)" if lacks else str(error))) from None
    table = table.sort_by("index")
    found = {"state": vectors(table.column("observation.state")).astype(np.float32),
             "action": vectors(table.column("action")).astype(np.float32),
             "index": table.column("index").to_numpy()}
    if objects:
        found["objects"] = vectors(table.column(ENVIRONMENT_STATE)).astype(
            np.float32).reshape(-1, *OBJECTS_SHAPE)
    return found


def _video_segments(root: Path, info: dict, episodes: list[dict], camera: str):
    """(file, first frame, frame count) per episode for one camera."""
    key, fps = image_key(camera), info["fps"]
    for episode in episodes:
        if info["codebase_version"] == lerobot_v21.VERSION:
            chunk = episode["episode_index"] // info["chunks_size"]
            name = info["video_path"].format(episode_chunk=chunk, video_key=key,
                                             episode_index=episode["episode_index"])
            yield root / name, 0, episode["length"]
        else:
            name = info["video_path"].format(
                video_key=key, chunk_index=episode[f"videos/{key}/chunk_index"],
                file_index=episode[f"videos/{key}/file_index"])
            first = round(episode[f"videos/{key}/from_timestamp"] * fps)
            yield root / name, first, episode["length"]


def _camera(root: Path, info: dict, episodes: list[dict], camera: str, factor: int,
            progress, cache: Path | None) -> np.ndarray:
    if image_key(camera) not in info.get("features", {}):
        raise DatasetError(f"{root}: no camera {camera!r} in the dataset")
    path = None
    if cache is not None:
        # (the counts as given, of any type: they only tell datasets apart)
        identity = json.dumps([str(root.resolve()), info.get("total_frames"),
                               info.get("total_episodes"), (root / "meta" / "info.json").stat()
                               .st_mtime_ns, camera, factor])
        path = cache / f"{hashlib.sha256(identity.encode()).hexdigest()[:16]}.npy"
        if path.is_file():
            if progress:
                progress(len(episodes))
            return np.load(path, mmap_mode="r")
    segments = list(_video_segments(root, info, episodes, camera))
    by_file: dict[Path, list[int]] = {}
    for position, (file, _, _) in enumerate(segments):
        by_file.setdefault(file, []).append(position)
    needed = {file: max(segments[p][1] + segments[p][2] for p in positions)
              for file, positions in by_file.items()}
    parts: list[np.ndarray | None] = [None] * len(segments)
    with ThreadPoolExecutor(max(1, min(4, os.cpu_count() or 1))) as pool:
        decoded = pool.map(lambda file: _decode(file, factor, needed[file]), by_file)
        for file, frames in zip(by_file, decoded, strict=True):
            for position in by_file[file]:  # a v3.0 file holds several episodes
                _, first, count = segments[position]
                if first + count > len(frames):
                    raise DatasetError(f"{file}: {len(frames)} frames, episode "
                                       f"{episodes[position]['episode_index']} needs frames "
                                       f"{first}..{first + count - 1}")
                parts[position] = frames[first:first + count]
                if progress:
                    progress(1)
    result = np.concatenate(parts)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_name(f"{path.stem}.{os.getpid()}.partial.npy")
        np.save(partial, result)
        partial.replace(path)
    return result


def _decode(file: Path, factor: int, frames: int) -> np.ndarray:
    """A video's first `frames` frames (as many as its episodes need), shrunk by `factor`."""
    problem = file_problem(file, MAX_VIDEO_BYTES)
    if problem:
        raise DatasetError(f"{file}: {problem}")
    try:
        with av.open(str(file)) as container:
            return np.stack([downsample(frame.to_ndarray(format="rgb24"), factor)
                             for frame in islice(container.decode(video=0), frames)])
    except (OSError, ValueError, av.FFmpegError) as error:
        raise DatasetError(f"{file}: cannot decode ({error})") from None
