"""The parts of `robofollow dataset check`: its report, the dataset's JSON files, and the checks
LeRobot's two layouts share (info.json, episode frames, statistics, videos, totals, tasks)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import av
import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from robofollow.data import lerobot_v30
from robofollow.data.lerobot import VIDEO_KEYS
from robofollow.data.stats import BINS, QUANTILE_KEYS, array_stats
from robofollow.files import (
    file_problem,
    json_lines,
    number_problem,
    read_file_at_most,
    read_json_object,
    shown,
)
from robofollow.sim import robot
from robofollow.sim.objects import FLAT as OBJECTS_WIDTH
from robofollow.sim.video import probe

WIDTH = len(robot.JOINT_NAMES)
VECTOR_FEATURES = {"observation.state": WIDTH, "action": WIDTH}  # every dataset has them
# where a dataset declares it: the objects observation, flattened
OPTIONAL_VECTORS = {"observation.environment_state": OBJECTS_WIDTH}
SCALAR_FEATURES = {"timestamp": "float32", "frame_index": "int64", "episode_index": "int64",
                   "index": "int64", "task_index": "int64"}
STATS_TOLERANCE = 1e-4  # absolute, on recomputed state/action statistics
TIME_TOLERANCE = 1e-4  # s
# the largest a dataset's files are read (training reads them alike): a JSON file, info.json (a
# generated one: about 9 KB) or stats.json; a JSON Lines file, of which episodes_stats.jsonl is
# the largest (about 40 KB an episode: 150 MB for the benchmark's 3,750 demonstrations, 460 MB
# with --instructions all; episodes.jsonl takes 280 bytes an episode); a parquet file (v2.1's
# hold an episode, about 21 KB; v3.0's are closed at DATA_FILE_MB, LeRobot's default); a video
# (v2.1's hold an episode, about 0.5 MB at 320x240; v3.0's are closed at VIDEO_FILE_MB)
MAX_JSON_BYTES = 16 * 1024 * 1024
MAX_JSONL_BYTES = 1 << 30
MAX_PARQUET_BYTES = 10 * lerobot_v30.DATA_FILE_MB << 20
MAX_VIDEO_BYTES = 4 * lerobot_v30.VIDEO_FILE_MB << 20
MAX_HDF5_BYTES = 2 << 30  # an HDF5 episode: about 35 KB a frame at 320x240 (4.3 MB for a
#   123-step pick-up), 0.7 MB a frame uncompressed


@dataclass(frozen=True)
class Kind:
    """What a field holds: whether a value is of it (`test`), and `what` it is, in words."""

    test: Callable[[Any], bool]
    what: str


def _whole(value, low: int = 0) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= low


TEXT = Kind(lambda value: isinstance(value, str), "a string")
TEXTS = Kind(lambda value: isinstance(value, list) and all(isinstance(v, str) for v in value),
             "a list of strings")
WHOLE = Kind(_whole, "a whole number from 0")
WHOLES = Kind(lambda value: isinstance(value, list) and all(map(_whole, value)),
              "a list of whole numbers from 0")
NUMBER = Kind(lambda value: number_problem(value) is None, "a finite number")
OBJECT = Kind(lambda value: isinstance(value, dict), "an object")
NAMES = Kind(lambda value: value is None or isinstance(value, list | dict),
             "null, a list or an object")  # a feature's names: LeRobot writes all three
# the fields of info.json, of a feature in it, and of the records of LeRobot's JSON Lines files
INFO_KINDS = {"fps": Kind(lambda value: NUMBER.test(value) and value > 0, "a positive number"),
              "total_episodes": WHOLE, "total_frames": WHOLE, "total_tasks": WHOLE,
              "total_videos": WHOLE, "total_chunks": WHOLE,
              "chunks_size": Kind(lambda value: _whole(value, 1), "a whole number from 1"),
              "data_path": TEXT, "video_path": TEXT, "features": OBJECT}
FEATURE_KINDS = {"dtype": TEXT, "shape": WHOLES, "names": NAMES}
EPISODE_KINDS = {"episode_index": WHOLE, "tasks": TEXTS, "length": WHOLE}
TASK_KINDS = {"task_index": WHOLE, "task": TEXT}
STATS_KINDS = {"episode_index": WHOLE, "stats": OBJECT}


def kind_problem(data: dict, kinds: dict[str, Kind], required: bool = False) -> str | None:
    """The first of `kinds`' fields that `data` holds with a value not of its kind ('fps is
    "a", not a positive number'), or, `required`, lacks ("no 'fps'"); None when there is none."""
    for key, kind in kinds.items():
        if key not in data:
            if required:
                return f"no {key!r}"
        elif not kind.test(data[key]):
            return f"{key} is {shown(data[key])}, not {kind.what}"
    return None


@dataclass
class Report:
    format: str = "unknown"
    episodes: int = 0
    frames: int = 0
    errors: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # worth knowing, not a problem

    def error(self, where: str, message: str) -> None:
        self.errors.append(f"{where}: {message}")

    def note(self, message: str) -> None:
        if message not in self.notes:
            self.notes.append(message)

    @property
    def ok(self) -> bool:
        return not self.errors

    def to_dict(self) -> dict:
        return {"format": self.format, "episodes": self.episodes, "frames": self.frames,
                "ok": self.ok, "errors": self.errors, "notes": self.notes}

    def render(self, limit: int = 50) -> str:
        head = (f"{self.format} dataset: {self.episodes} episodes, {self.frames} frames: "
                + ("valid" if self.ok else f"{len(self.errors)} problem(s)"))
        lines = [head] + [f"  - {e}" for e in self.errors[:limit]] + [
            f"  note: {n}" for n in self.notes]
        if len(self.errors) > limit:
            lines.append(f"  ... and {len(self.errors) - limit} more (--json lists all)")
        return "\n".join(lines)


def load_json(path: Path, report: Report) -> dict | None:
    """A JSON object file (at most MAX_JSON_BYTES), or None (reported)."""
    data, problem = read_json_object(path, MAX_JSON_BYTES)
    if problem:
        report.error(path.name, f"unreadable: {problem}")
    return data


def load_jsonl(path: Path, report: Report, kinds: dict[str, Kind]) -> list[dict]:
    """The records of a JSON Lines file (at most MAX_JSONL_BYTES): objects with each of
    `kinds`' fields, of its kind. Each line that is not one is reported, and the file then
    read as no records."""
    data, problem = read_file_at_most(path, MAX_JSONL_BYTES)
    if problem:
        report.error(path.name, f"unreadable: {problem}")
        return []
    records, complete = [], True
    for line in json_lines(data):
        problem = line.problem or (kind_problem(line.value, kinds, required=True)
                                   if isinstance(line.value, dict) else
                                   f"{shown(line.value)} is not a JSON object")
        if problem:
            report.error(f"{path.name}:{line.number}:{line.column or 1}", problem)
            complete = False
        records.append(line.value)
    return records if complete else []


def check_rows(rows: list[dict], where: str, kinds: dict[str, Kind], report: Report) -> bool:
    """Whether each row of a table has each of `kinds`' fields, of its kind; the first that
    has not is reported."""
    for number, row in enumerate(rows):
        problem = kind_problem(row, kinds, required=True)
        if problem:
            report.error(where, f"row {number}: {problem}")
            return False
    return True


def vector_widths(features: dict) -> dict[str, int]:
    """The vector features a dataset holds, with their widths: state and action, and the
    optional ones its info declares."""
    return {**VECTOR_FEATURES, **{key: width for key, width in OPTIONAL_VECTORS.items()
                                  if key in features}}


def check_info(info: dict, report: Report, required: tuple[str, ...]) -> dict:
    """The feature schema and top-level fields; returns the features (or {}: a field of the
    wrong type is the one finding)."""
    for key in ("robot_type", "fps", "total_episodes", "total_frames", "total_tasks",
                "data_path", "features") + required:
        if key not in info:
            report.error("meta/info.json", f"missing {key!r}")
    problem = _info_problem(info)
    if problem:
        report.error("meta/info.json", problem)
        return {}
    features = info.get("features", {})
    for key, width in vector_widths(features).items():
        feature = features.get(key)
        if feature is None:
            report.error("meta/info.json", f"feature {key!r} is missing")
        elif (feature.get("dtype"), list(feature.get("shape", []))) != ("float32", [width]):
            report.error("meta/info.json", f"{key} must be float32 [{width}], got "
                         f"{feature.get('dtype')} {feature.get('shape')}")
        elif feature.get("names") and len(feature["names"]) != width:
            report.error("meta/info.json", f"{key} has {len(feature['names'])} names for "
                         f"{width} values")
    for key, dtype in SCALAR_FEATURES.items():
        if features.get(key, {}).get("dtype") != dtype:
            report.error("meta/info.json", f"feature {key!r} must be {dtype}")
    for key in VIDEO_KEYS:
        feature = features.get(key, {})
        shape = feature.get("shape", [])
        if feature.get("dtype") != "video" or len(shape) != 3 or shape[2] != 3:
            report.error("meta/info.json", f"{key} must be a video feature of shape [H, W, 3]")
    return features


def _info_problem(info: dict) -> str | None:
    """The first field of info.json, or of a feature in it, of the wrong kind, or None."""
    problem = kind_problem(info, INFO_KINDS)
    if problem:
        return problem
    for key, feature in info.get("features", {}).items():
        if not isinstance(feature, dict):
            return f"features.{key} is {shown(feature)}, not {OBJECT.what}"
        problem = kind_problem(feature, FEATURE_KINDS)
        if problem:
            return f"features.{key}.{problem}"
    return None


def vector_column(column: pa.ChunkedArray, width: int) -> bool:
    """Whether a column holds `width` float32 values a row: a fixed-size list, as this project
    and LeRobot's writer store it, or a plain list with that many values in every row, as
    LeRobot's v2.1 -> v3.0 converter does."""
    kind = column.type
    if pa.types.is_fixed_size_list(kind):
        return kind.list_size == width and kind.value_type == pa.float32()
    if not (pa.types.is_list(kind) or pa.types.is_large_list(kind)) \
            or kind.value_type != pa.float32() or column.null_count:
        return False
    lengths = pc.list_value_length(column.combine_chunks()).to_numpy()
    return bool(np.all(lengths == width))


def check_frames(table: pa.Table, where: str, episode: int, length: int, start: int,
                  task_index: int, fps: float, report: Report,
                  vectors: dict[str, int]) -> dict[str, np.ndarray]:
    """One episode's frames: columns, dtypes, count, indices, timestamps, finite values.
    Returns its vector features (`vectors`: name -> width) as [N, width] arrays, where their
    columns are of a valid type."""
    missing = [c for c in (*vectors, *SCALAR_FEATURES) if c not in table.column_names]
    if missing:
        report.error(where, f"missing columns {missing}")
        return {}
    if table.num_rows != length:
        report.error(where, f"{table.num_rows} frames, the episode table says {length}")
    arrays = {}
    for key, width in vectors.items():
        if not vector_column(table.column(key), width):
            report.error(where, f"{key} is {table.schema.field(key).type}, expected "
                         f"fixed_size_list<float>[{width}] (or a list of {width} floats a row)")
            continue
        arrays[key] = table.column(key).combine_chunks().flatten().to_numpy().reshape(-1, width)
        if not np.all(np.isfinite(arrays[key])):
            report.error(where, f"{key} has non-finite values")
    for key, dtype in SCALAR_FEATURES.items():
        if table.schema.field(key).type != pa.from_numpy_dtype(np.dtype(dtype)):
            report.error(where, f"{key} is {table.schema.field(key).type}, expected {dtype}")
    n = table.num_rows
    frames = table.column("frame_index").to_numpy()
    if not np.array_equal(frames, np.arange(n)):
        report.error(where, "frame_index is not 0, 1, ... in order")
    if not np.all(table.column("episode_index").to_numpy() == episode):
        report.error(where, f"episode_index is not {episode} throughout")
    if not np.array_equal(table.column("index").to_numpy(), start + np.arange(n)):
        report.error(where, f"index is not {start}, {start + 1}, ... (global frame order)")
    if not np.all(table.column("task_index").to_numpy() == task_index):
        report.error(where, f"task_index is not {task_index} throughout")
    times = table.column("timestamp").to_numpy().astype(np.float64)
    if np.abs(times - np.arange(n) / fps).max(initial=0.0) > TIME_TOLERANCE:
        report.error(where, f"timestamp is not frame_index / fps ({fps})")
    return arrays


QUANTILE_NOTE = ("the statistics have no quantiles (q01 ... q99): LeRobot's policies that "
                 "normalise by quantiles (pi0.5) need them; LeRobot's "
                 "augment_dataset_quantile_stats script adds them")


def check_stored(stats: dict, where: str, report: Report, quantiles_expected: bool,
                  vectors: dict[str, int]) -> list[str]:
    """Stored statistics of state, action and images: every statistic present, state and
    action as WIDTH values, images as 3 x 1 x 1 values in [0, 1], min <= q01 <= q10 <= q50 <=
    q90 <= q99 <= max in every dimension. A feature's quantiles are checked when it has one
    of them, and then all of them; a feature with none is a note where they are expected
    (v3.0: LeRobot >= 0.4 writes them, its v2.1 converter and LeRobot 0.3.x did not). Returns
    the features whose statistics are complete and of the right shape."""
    usable = []
    for key in (*vectors, *VIDEO_KEYS):
        stored = stats.get(key)
        if not isinstance(stored, dict):
            report.error(where, f"no statistics for {key}")
            continue
        image = key in VIDEO_KEYS
        has_quantiles = bool(set(QUANTILE_KEYS) & stored.keys())
        if quantiles_expected and not has_quantiles:
            report.note(QUANTILE_NOTE)
        quantiles = QUANTILE_KEYS if has_quantiles else ()
        names = ("min", *quantiles, "max", "mean", "std")
        missing = [n for n in names + ("count",) if n not in stored]
        if missing:
            report.error(where, f"{key} statistics lack {missing}")
            continue
        try:
            values = np.array([stored[n] for n in names], dtype=np.float64)
        except (TypeError, ValueError):
            values = np.empty(0)
        if image and (values.shape[1:] != (3, 1, 1) or values.min() < -STATS_TOLERANCE
                      or values.max() > 1 + STATS_TOLERANCE):
            report.error(where, f"{key} statistics must be 3 x 1 x 1 values in [0, 1]")
        elif not image and values.shape[1:] != (vectors[key],):
            report.error(where, f"{key} statistics must be {vectors[key]} values each")
        elif np.any(np.diff(values[:len(quantiles) + 2], axis=0) < -STATS_TOLERANCE):
            report.error(where, f"{key} statistics are not ordered min <= "
                         f"{' <= '.join(quantiles)} <= max")
        else:
            usable.append(key)
    return usable


def check_stats(stats: dict, arrays: dict[str, np.ndarray], where: str, report: Report,
                 quantiles_expected: bool, vectors: dict[str, int]) -> None:
    """Stored episode statistics (`check_stored`), state and action against the frames'
    (`arrays`, from `check_frames`; a quantile, where stored, within one histogram bin of its
    recomputed estimate)."""
    for key in check_stored(stats, where, report, quantiles_expected, vectors):
        if key not in arrays:  # an image, or a column check_frames reported
            continue
        expected = array_stats(arrays[key])
        bin_width = (np.asarray(expected["max"]) - expected["min"]) / BINS
        quantiles = [q for q in QUANTILE_KEYS if q in stats[key]]  # all or none (checked)
        for name in ("min", "max", "mean", "std", *quantiles):
            tolerance = STATS_TOLERANCE + (bin_width if name in QUANTILE_KEYS else 0)
            if np.any(np.abs(np.asarray(stats[key][name]) - expected[name]) > tolerance):
                report.error(where, f"{key} {name} does not match the frames")
        if list(np.ravel(stats[key]["count"])) != expected["count"]:
            report.error(where, f"{key} count {stats[key]['count']} is not {expected['count']}")


def check_video(path: Path, feature: dict, fps: float, report: Report,
                 where: str) -> list[float] | None:
    """Opens, has the feature's resolution and the dataset's frame rate; its frame times (or
    None when unusable)."""
    if not path.exists():
        report.error(where, f"missing video {path.name}")
        return None
    problem = file_problem(path, MAX_VIDEO_BYTES)
    if problem:
        report.error(where, f"video {path.name}: {problem}")
        return None
    try:
        video = probe(path)
    except (av.FFmpegError, IndexError) as error:
        report.error(where, f"unreadable video: {error}")
        return None
    if abs(video.fps - fps) > 1e-3:
        report.error(where, f"video runs at {video.fps:g} frames/s, the dataset at {fps:g}")
    height, width = feature["shape"][:2]
    if (video.height, video.width) != (height + height % 2, width + width % 2):
        report.error(where, f"video is {video.width}x{video.height}, the feature says "
                     f"{width}x{height}")
    return video.times


def check_totals(info: dict, lengths: list[int], report: Report, tasks: int | None = None,
                  where: str = "meta/info.json") -> None:
    report.episodes, report.frames = len(lengths), sum(lengths)
    totals = [("total_episodes", len(lengths)), ("total_frames", sum(lengths))]
    for key, value in totals + ([("total_tasks", tasks)] if tasks is not None else []):
        if info.get(key) != value:
            report.error(where, f"{key} is {info.get(key)}, the dataset has {value}")


def check_sequence(indices: list, where: str, what: str, report: Report) -> bool:
    if indices != list(range(len(indices))):
        report.error(where, f"{what} are not 0 .. {len(indices) - 1} in order")
        return False
    return True


def read_parquets(folder: Path, report: Report) -> pa.Table | None:
    files = sorted(folder.glob("chunk-*/file-*.parquet"))
    where = str(folder.relative_to(folder.parent.parent))
    if not files:
        report.error(where, "no parquet files")
        return None
    for file in files:
        problem = file_problem(file, MAX_PARQUET_BYTES)
        if problem:
            report.error(f"{where}/{file.relative_to(folder)}", f"unreadable: {problem}")
            return None
    try:
        return pa.concat_tables([pq.read_table(f) for f in files])
    except (OSError, pa.ArrowException) as error:
        report.error(where, f"unreadable: {error}")
        return None


def read_tasks(path: Path, report: Report) -> list[dict] | None:
    """meta/tasks.parquet as [{"task", "task_index"}], or None (reported). LeRobot writes a
    pandas frame of task_index indexed by the task strings, the index stored as a column named
    "task" (LeRobot >= 0.5, and this project) or "__index_level_0__" (unnamed, LeRobot 0.4.x)
    and listed in the schema's pandas metadata (index_columns); a plain "task" column is read
    too."""
    where = "meta/tasks.parquet"
    problem = file_problem(path, MAX_PARQUET_BYTES)
    if problem:
        report.error(where, f"unreadable: {problem}")
        return None
    try:
        table = pq.read_table(path)
        metadata = table.schema.pandas_metadata
    except (OSError, ValueError, pa.ArrowException) as error:
        report.error(where, f"unreadable: {error}")
        return None
    pandas_index = metadata.get("index_columns") if isinstance(metadata, dict) else None
    candidates = ["task", *(pandas_index if isinstance(pandas_index, list) else []),
                  "__index_level_0__"]
    column = next((c for c in candidates if c in table.column_names), None)
    if column is None or "task_index" not in table.column_names:
        report.error(where, "expected a task_index column and the task strings in a 'task' "
                     "column or as the pandas index (index_columns in the pandas metadata, or "
                     f"__index_level_0__); found columns {table.column_names}")
        return None
    tasks, indices = table.column(column), table.column("task_index")
    text = pa.types.is_string(tasks.type) or pa.types.is_large_string(tasks.type)
    if not (text and pa.types.is_integer(indices.type)):
        report.error(where, f"expected string tasks and integer task_index, got {column} "
                     f"{tasks.type} and task_index {indices.type}")
        return None
    return [{"task": task, "task_index": index}
            for task, index in zip(tasks.to_pylist(), indices.to_pylist(), strict=True)]
