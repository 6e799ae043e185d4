"""`robofollow dataset check DIR`: validate a dataset against its format's rules.

LeRobot v2.1 / v3.0: info.json fields and feature schema (dtypes, shapes, names), episode and
task tables (contiguous indices, totals; tasks.parquet in each layout LeRobot writes), every
episode's frames (columns, dtypes, row count, frame/episode/global indices, timestamps =
frame_index / fps, finite values), every video (it opens, resolution, frame count against the
episode length) and the statistics (quantiles checked where present; a v3.0 dataset without
them, as LeRobot's v2.1 converter leaves it, gets a note; state and action recomputed from the
frames and compared). HDF5: info, index and each file's arrays and attributes.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from robofollow.data import hdf5_export, lerobot_v21, lerobot_v30
from robofollow.data.check_parts import (
    EPISODE_KINDS,
    MAX_HDF5_BYTES,
    MAX_PARQUET_BYTES,
    NUMBER,
    STATS_KINDS,
    TASK_KINDS,
    TEXT,
    TIME_TOLERANCE,
    WHOLE,
    WHOLES,
    WIDTH,
    Kind,
    Report,
    check_frames,
    check_info,
    check_rows,
    check_sequence,
    check_stats,
    check_stored,
    check_totals,
    check_video,
    kind_problem,
    load_json,
    load_jsonl,
    read_parquets,
    read_tasks,
    vector_widths,
)
from robofollow.data.lerobot import VIDEO_KEYS
from robofollow.files import file_problem, shown
from robofollow.sim.cameras import CAMERA_NAMES
from robofollow.sim.objects import FLAT as OBJECTS_WIDTH


def check(root: Path) -> Report:
    """The dataset at `root` checked against its format's rules (LeRobot v2.1 / v3.0, HDF5)."""
    report = Report()
    if (root / "meta" / "info.json").is_file():
        info = load_json(root / "meta" / "info.json", report)
        version = info.get("codebase_version") if info else None
        report.format = f"lerobot-{version}"
        if version == lerobot_v21.VERSION:
            _check_v21(root, info, report)
        elif version == lerobot_v30.VERSION:
            _check_v30(root, info, report)
        elif info is not None:
            report.error("meta/info.json", f"codebase_version {version!r} is not v2.1 or v3.0")
    elif (root / "info.json").is_file():
        report.format = "hdf5"
        info = load_json(root / "info.json", report)
        if info is not None:
            _check_hdf5(root, info, report)
    else:
        report.error(str(root), "no meta/info.json (LeRobot) or info.json (HDF5): not a dataset")
    return report


# -- LeRobot, shared -------------------------------------------------------------------------

def _read_frames(root: Path, name: str, where: str, report: Report) -> pa.Table | None:
    """The frames in the dataset's file `name` (an episode's, v2.1; a file of episodes',
    v3.0): a parquet file of at most MAX_PARQUET_BYTES; else None, reported at `where`."""
    problem = file_problem(root / name, MAX_PARQUET_BYTES)
    if not problem:
        try:
            return pq.read_table(root / name)
        except (OSError, pa.ArrowException) as error:
            problem = str(error)
    report.error(where, f"cannot read {name}: {problem}")
    return None


# -- LeRobot v2.1 ----------------------------------------------------------------------------

def _paths_known(info: dict, templates: dict[str, tuple[str, ...]], report: Report) -> bool:
    """Whether info.json's path templates take the fields the check fills in (each that does
    not is a finding: it would fail when formatted; one that is not text check_info names)."""
    for key, fields in templates.items():
        if not isinstance(info.get(key), str):
            return False
        try:
            info[key].format(**{field: VIDEO_KEYS[0] if field == "video_key" else 0
                                for field in fields})
        except (AttributeError, KeyError, IndexError, TypeError, ValueError):
            report.error("meta/info.json", f"{key} is {shown(info.get(key))}, not a path "
                         f"template of {', '.join(fields)}")
            return False
    return True


V21_PATHS = {"data_path": ("episode_chunk", "episode_index"),
             "video_path": ("episode_chunk", "video_key", "episode_index")}
V30_PATHS = {"data_path": ("chunk_index", "file_index"),
             "video_path": ("video_key", "chunk_index", "file_index")}


def _check_v21(root: Path, info: dict, report: Report) -> None:
    features = check_info(info, report, ("video_path", "chunks_size", "total_chunks"))
    if not _paths_known(info, V21_PATHS, report):
        return
    vectors = vector_widths(features)
    meta = root / "meta"
    episodes = load_jsonl(meta / "episodes.jsonl", report, EPISODE_KINDS)
    tasks = load_jsonl(meta / "tasks.jsonl", report, TASK_KINDS)
    stats = {r["episode_index"]: r["stats"]
             for r in load_jsonl(meta / "episodes_stats.jsonl", report, STATS_KINDS)}
    check_sequence([t["task_index"] for t in tasks], "meta/tasks.jsonl", "task indices",
                    report)
    task_index = {t["task"]: t["task_index"] for t in tasks}
    if not check_sequence([e["episode_index"] for e in episodes], "meta/episodes.jsonl",
                           "episode indices", report) or report.errors:
        return
    check_totals(info, [e["length"] for e in episodes], report, len(tasks))
    fps, chunk_size, start = info["fps"], info["chunks_size"], 0
    for record in episodes:
        index, length = record["episode_index"], record["length"]
        where = f"episode {index}"
        if len(record["tasks"]) != 1 or record["tasks"][0] not in task_index:
            report.error(where, f"tasks {record['tasks']} are not one task of tasks.jsonl")
            continue
        chunk = index // chunk_size
        table = _read_frames(root, info["data_path"].format(episode_chunk=chunk,
                                                            episode_index=index), where, report)
        if table is None:
            start += length
            continue
        arrays = check_frames(table, where, index, length, start,
                               task_index[record["tasks"][0]], fps, report, vectors)
        start += length
        if index not in stats:
            report.error(where, "no entry in episodes_stats.jsonl")
        else:
            check_stats(stats[index], arrays, where, report, quantiles_expected=False,
                         vectors=vectors)
        for key in VIDEO_KEYS:
            video = root / info["video_path"].format(episode_chunk=chunk, video_key=key,
                                                     episode_index=index)
            times = check_video(video, features[key], fps, report, f"{where} {key}")
            if times is not None and len(times) != length:
                report.error(f"{where} {key}", f"video has {len(times)} frames, the episode "
                             f"{length}")


# -- LeRobot v3.0 ----------------------------------------------------------------------------

# the fields of an episode's row that the check reads (LeRobot's; the statistics apart)
V30_ROW_KINDS = {**EPISODE_KINDS, "dataset_from_index": WHOLE, "dataset_to_index": WHOLE,
                 "data/chunk_index": WHOLE, "data/file_index": WHOLE,
                 **{f"videos/{key}/{field}": kind for key in VIDEO_KEYS for field, kind in (
                     ("chunk_index", WHOLE), ("file_index", WHOLE),
                     ("from_timestamp", NUMBER), ("to_timestamp", NUMBER))}}

def _check_v30(root: Path, info: dict, report: Report) -> None:
    features = check_info(info, report, ("video_path", "chunks_size"))
    if not _paths_known(info, V30_PATHS, report):
        return
    vectors = vector_widths(features)
    meta = root / "meta"
    tasks = read_tasks(meta / "tasks.parquet", report)
    if tasks is None:
        return
    episodes = read_parquets(meta / "episodes", report)
    if episodes is None:
        return
    rows = episodes.to_pylist()
    check_sequence([t["task_index"] for t in tasks], "meta/tasks.parquet", "task indices",
                    report)
    task_index = {t["task"]: t["task_index"] for t in tasks}
    if not check_rows(rows, "meta/episodes", V30_ROW_KINDS, report) or not check_sequence(
            [r["episode_index"] for r in rows], "meta/episodes", "episode indices", report) \
            or report.errors:
        return
    check_totals(info, [r["length"] for r in rows], report, len(tasks))
    fps, data_files, video_times = info["fps"], {}, {}
    start = 0
    for row in rows:
        index, length = row["episode_index"], row["length"]
        where = f"episode {index}"
        if len(row["tasks"]) != 1 or row["tasks"][0] not in task_index:
            report.error(where, f"tasks {row['tasks']} are not one task of tasks.parquet")
            continue
        if (row["dataset_from_index"], row["dataset_to_index"]) != (start, start + length):
            report.error(where, f"frames {row['dataset_from_index']}..{row['dataset_to_index']}"
                         f", expected {start}..{start + length}")
        name = info["data_path"].format(chunk_index=row["data/chunk_index"],
                                        file_index=row["data/file_index"])
        if name not in data_files:
            data_files[name] = _read_frames(root, name, where, report)
            if data_files[name] is None:
                return
        table = data_files[name]  # a file holds consecutive frames: slice the episode out
        offset = row["dataset_from_index"] - (table.column("index")[0].as_py()
                                              if table.num_rows else 0)
        frames = table.slice(max(offset, 0), length)
        arrays = check_frames(frames, where, index, length, start,
                               task_index[row["tasks"][0]], fps, report, vectors)
        stats = {key.split("/")[1]: {} for key in row if key.startswith("stats/")}
        for key, value in row.items():
            if key.startswith("stats/") and value is not None:  # null: another row has it
                _, feature, stat = key.split("/")
                stats[feature][stat] = value
        check_stats(stats, arrays, where, report, quantiles_expected=True, vectors=vectors)
        start += length
        for key in VIDEO_KEYS:
            video = info["video_path"].format(video_key=key,
                                              chunk_index=row[f"videos/{key}/chunk_index"],
                                              file_index=row[f"videos/{key}/file_index"])
            if video not in video_times:
                video_times[video] = check_video(root / video, features[key], fps, report,
                                                  video)
            times = video_times[video]
            if times is None:
                continue
            low, high = row[f"videos/{key}/from_timestamp"], row[f"videos/{key}/to_timestamp"]
            inside = int(np.searchsorted(times, high - TIME_TOLERANCE)
                         - np.searchsorted(times, low - TIME_TOLERANCE))
            if inside != length or abs(high - low - length / fps) > TIME_TOLERANCE:
                report.error(f"{where} {key}", f"{inside} video frames in {low:.3f}..{high:.3f}"
                             f" s, the episode has {length}")
    if not (meta / "stats.json").is_file():
        report.error("meta/stats.json", "missing")
    else:
        stats = load_json(meta / "stats.json", report)
        if stats is not None:
            check_stored(stats if isinstance(stats, dict) else {}, "meta/stats.json", report,
                          quantiles_expected=True, vectors=vectors)


# -- HDF5 ------------------------------------------------------------------------------------

HDF5_INFO_KINDS = {"image_shape": Kind(lambda value: WHOLES.test(value) and len(value) == 3,
                                       "a list of 3 whole numbers")}
HDF5_EPISODE_KINDS = {"episode_index": WHOLE, "file": TEXT, "length": WHOLE}


def _check_hdf5(root: Path, info: dict, report: Report) -> None:
    if info.get("format") != hdf5_export.VERSION:
        report.error("info.json", f"format {info.get('format')!r} is not "
                     f"{hdf5_export.VERSION}")
        return
    problem = kind_problem(info, HDF5_INFO_KINDS, required=True)
    if problem:
        report.error("info.json", problem)
        return
    episodes = load_jsonl(root / "episodes.jsonl", report, HDF5_EPISODE_KINDS)
    if not check_sequence([e["episode_index"] for e in episodes], "episodes.jsonl",
                           "episode indices", report) or report.errors:
        return
    height, width, _ = info["image_shape"]
    lengths = []
    for record in episodes:
        where = f"episode {record['episode_index']}"
        lengths.append(record["length"])
        problem = file_problem(root / record["file"], MAX_HDF5_BYTES)
        if problem:
            report.error(where, f"cannot read {record['file']}: {problem}")
            continue
        try:
            with h5py.File(root / record["file"], "r") as h5:
                widths = {"action": WIDTH, "observations/qpos": WIDTH,
                          **({"observations/environment_state": OBJECTS_WIDTH}
                             if "observations/environment_state" in h5 else {})}
                for name, size in widths.items():
                    data = h5[name]
                    if data.dtype != np.float32 or data.shape != (record["length"], size):
                        report.error(where, f"{name} is {data.dtype} {data.shape}, expected "
                                     f"float32 {(record['length'], size)}")
                    elif not np.all(np.isfinite(data[()])):
                        report.error(where, f"{name} has non-finite values")
                for camera in CAMERA_NAMES:
                    data = h5[f"observations/images/{camera}"]
                    if data.dtype != np.uint8 or data.shape != (record["length"], height,
                                                                 width, 3):
                        report.error(where, f"images/{camera} is {data.dtype} {data.shape}")
                if json.loads(h5["instructions"][()]) != record["instructions"]:
                    report.error(where, "instructions differ from episodes.jsonl")
        except (OSError, KeyError, ValueError) as error:  # (ValueError: instructions that
            #   are not JSON, or not text)
            report.error(where, f"cannot read {record['file']}: {error}")
    check_totals(info, lengths, report, where="info.json")
