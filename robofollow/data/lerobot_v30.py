"""LeRobot v3.0: many episodes per parquet file and per mp4 (file-NNN), episode metadata and
statistics in parquet, tasks in meta/tasks.parquet, global statistics in meta/stats.json."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from robofollow.data import lerobot
from robofollow.data.lerobot import CHUNKS_SIZE, FPS, VIDEO_KEYS, Episode
from robofollow.data.stats import aggregate
from robofollow.files import write_json
from robofollow.sim.video import concatenate

VERSION = "v3.0"
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
EPISODES_PATH = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
DATA_FILE_MB = 100  # LeRobot's defaults: a new file once one would grow past this
VIDEO_FILE_MB = 500


def file_groups(sizes: list[int], limit: int) -> list[list[int]]:
    """Consecutive items packed into files of at most `limit` bytes (an item larger than
    the limit gets a file of its own)."""
    groups: list[list[int]] = []
    used = 0
    for item, size in enumerate(sizes):
        if not groups or used + size > limit:
            groups.append([])
            used = 0
        groups[-1].append(item)
        used += size
    return groups


def location(file_number: int) -> dict[str, int]:
    return {"chunk_index": file_number // CHUNKS_SIZE, "file_index": file_number % CHUNKS_SIZE}


def _write_data(out: Path, episode_list: list[Episode], rows: list[dict], progress) -> dict:
    """Frame tables, grouped into files; fills each row's data fields; returns the stats."""
    tables, stats, start = [], {}, 0
    for episode in episode_list:
        table = lerobot.frame_table(episode, lerobot.load_arrays(episode.unit), start)
        tables.append(table)
        stats[episode.index] = lerobot.episode_stats(episode, table)
        rows[episode.index].update({"dataset_from_index": start,
                                    "dataset_to_index": start + episode.length})
        start += episode.length
        if progress:
            progress()
    for number, group in enumerate(file_groups([t.nbytes for t in tables],
                                               DATA_FILE_MB * 2 ** 20)):
        where = location(number)
        path = out / DATA_PATH.format(**where)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.concat_tables([tables[i] for i in group]), path)
        for i in group:
            rows[i].update({"data/chunk_index": where["chunk_index"],
                            "data/file_index": where["file_index"]})
    return stats


def _write_videos(out: Path, episode_list: list[Episode], rows: list[dict]) -> None:
    for key in VIDEO_KEYS:
        sources = [episode.unit / f"{key}.mp4" for episode in episode_list]
        sizes = [source.stat().st_size for source in sources]
        for number, group in enumerate(file_groups(sizes, VIDEO_FILE_MB * 2 ** 20)):
            where = location(number)
            path = out / VIDEO_PATH.format(video_key=key, **where)
            path.parent.mkdir(parents=True, exist_ok=True)
            concatenate([sources[i] for i in group], path)
            elapsed = 0.0
            for i in group:
                duration = episode_list[i].length / FPS
                rows[i].update({f"videos/{key}/chunk_index": where["chunk_index"],
                                f"videos/{key}/file_index": where["file_index"],
                                f"videos/{key}/from_timestamp": elapsed,
                                f"videos/{key}/to_timestamp": elapsed + duration})
                elapsed += duration


def tasks_table(tasks: list[str]) -> pa.Table:
    """meta/tasks.parquet: task_index by task, with pandas metadata making `task` the index
    (LeRobot reads it with pandas.read_parquet and looks tasks up by index)."""
    table = pa.table({"task_index": pa.array(range(len(tasks)), pa.int64()),
                      "task": pa.array(tasks, pa.string())})
    pandas = {"index_columns": ["task"],
              "column_indexes": [{"name": None, "field_name": None, "pandas_type": "unicode",
                                  "numpy_type": "object", "metadata": {"encoding": "UTF-8"}}],
              "columns": [{"name": "task_index", "field_name": "task_index",
                           "pandas_type": "int64", "numpy_type": "int64", "metadata": None},
                          {"name": "task", "field_name": "task", "pandas_type": "unicode",
                           "numpy_type": "object", "metadata": None}],
              "creator": {"library": "pyarrow", "version": pa.__version__},
              "pandas_version": "2.2.0"}
    return table.replace_schema_metadata({"pandas": json.dumps(pandas)})


def write(out: Path, demos: list[tuple[dict, Path]], width: int, height: int,
          progress=None) -> int:
    """Write the dataset under `out` (empty of dataset files); returns the episode count."""
    episode_list, tasks = lerobot.episodes(demos)
    rows = [{"episode_index": e.index, "tasks": [e.task], "length": e.length, **e.metadata()}
            for e in episode_list]
    stats = _write_data(out, episode_list, rows, progress)
    _write_videos(out, episode_list, rows)
    for row in rows:
        row.update({"meta/episodes/chunk_index": 0, "meta/episodes/file_index": 0})
        for feature, values in stats[row["episode_index"]].items():
            row.update({f"stats/{feature}/{name}": value for name, value in values.items()})
    meta = out / "meta"
    (meta / "episodes" / "chunk-000").mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_pylist(rows), out / EPISODES_PATH.format(**location(0)))
    pq.write_table(tasks_table(tasks), meta / "tasks.parquet")
    features = stats[0].keys() if stats else []
    write_json(meta / "stats.json", {
        feature: aggregate([stats[e.index][feature] for e in episode_list])
        for feature in features})
    write_json(meta / "info.json", lerobot.info(
        VERSION, width, height, episode_list, tasks,
        {"chunks_size": CHUNKS_SIZE, "data_files_size_in_mb": DATA_FILE_MB,
         "video_files_size_in_mb": VIDEO_FILE_MB, "data_path": DATA_PATH,
         "video_path": VIDEO_PATH}))
    return len(episode_list)
