"""LeRobot v2.1: one parquet file and one mp4 per camera for each episode, JSON Lines metadata
(what openpi and GR00T read)."""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq

from robofollow.data import lerobot
from robofollow.data.lerobot import CHUNKS_SIZE, VIDEO_KEYS
from robofollow.files import link_or_copy, write_json, write_jsonl

VERSION = "v2.1"
DATA_PATH = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
VIDEO_PATH = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"


def write(out: Path, demos: list[tuple[dict, Path]], width: int, height: int,
          progress=None) -> int:
    """Write the dataset under `out` (empty of dataset files); returns the episode count."""
    episode_list, tasks = lerobot.episodes(demos)
    records, stats, start = [], [], 0
    for episode in episode_list:
        chunk = episode.index // CHUNKS_SIZE
        table = lerobot.frame_table(episode, lerobot.load_arrays(episode.unit), start)
        start += episode.length
        path = out / DATA_PATH.format(episode_chunk=chunk, episode_index=episode.index)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(table, path)
        for key in VIDEO_KEYS:
            link_or_copy(episode.unit / f"{key}.mp4", out / VIDEO_PATH.format(
                episode_chunk=chunk, video_key=key, episode_index=episode.index))
        records.append({"episode_index": episode.index, "tasks": [episode.task],
                        "length": episode.length, **episode.metadata()})
        stats.append({"episode_index": episode.index,
                      "stats": lerobot.episode_stats(episode, table)})
        if progress:
            progress()
    meta = out / "meta"
    write_jsonl(meta / "episodes.jsonl", records)
    write_jsonl(meta / "episodes_stats.jsonl", stats)
    write_jsonl(meta / "tasks.jsonl", [{"task_index": i, "task": task}
                                               for i, task in enumerate(tasks)])
    chunks = -(-len(episode_list) // CHUNKS_SIZE)
    write_json(meta / "info.json", lerobot.info(
        VERSION, width, height, episode_list, tasks,
        {"total_videos": len(episode_list) * len(VIDEO_KEYS), "total_chunks": chunks,
         "chunks_size": CHUNKS_SIZE, "data_path": DATA_PATH, "video_path": VIDEO_PATH}))
    return len(episode_list)
