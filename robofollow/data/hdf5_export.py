"""HDF5 datasets for trainers that want raw arrays: one file per demonstration with
`action` and `observations/qpos` (float32 (N, 14)), `observations/environment_state` (float32
(N, objects): the objects observation, flattened), `observations/images/<camera>` (uint8
(N, H, W, 3)), `instructions` (a JSON list) and the metadata as attributes; `episodes.jsonl`
and `info.json` beside them."""

from __future__ import annotations

from pathlib import Path

from robofollow.data.units import ROBOT_TYPE
from robofollow.files import link_or_copy, write_json, write_jsonl
from robofollow.sim import robot
from robofollow.sim.cameras import CAMERA_NAMES
from robofollow.sim.objects import FIELDS, FLAT
from robofollow.sim.simulation import CONTROL_HZ

VERSION = "robofollow-hdf5-v1"
EPISODE_PATH = "data/episode_{episode_index:06d}.hdf5"
META_FIELDS = ("label", "scene", "layout", "seed", "spec_digest", "length", "instructions")


def write(out: Path, demos: list[tuple[dict, Path]], width: int, height: int,
          progress=None) -> int:
    """Write the dataset under `out` (empty of dataset files); returns the episode count."""
    records = []
    for index, (demo, unit) in enumerate(demos):
        path = EPISODE_PATH.format(episode_index=index)
        link_or_copy(unit / "episode.hdf5", out / path)
        records.append({"episode_index": index, "file": path,
                        **{key: demo[key] for key in META_FIELDS}})
        if progress:
            progress()
    write_jsonl(out / "episodes.jsonl", records)
    write_json(out / "info.json", {
        "format": VERSION, "robot_type": ROBOT_TYPE, "fps": CONTROL_HZ,
        "total_episodes": len(records), "total_frames": sum(r["length"] for r in records),
        "episode_path": EPISODE_PATH, "joint_names": list(robot.JOINT_NAMES),
        "cameras": list(CAMERA_NAMES), "image_shape": [height, width, 3],
        "datasets": {"action": "float32 (N, 14): the joint target sent after observation t",
                     "observations/qpos": "float32 (N, 14): the joint state at t",
                     "observations/environment_state": (
                         f"float32 (N, {FLAT}): the objects observation at t, rows of "
                         f"{', '.join(FIELDS)}, flattened"),
                     "observations/images/<camera>": "uint8 (N, H, W, 3) RGB",
                     "instructions": "JSON list of the episode's instructions"}})
    return len(records)
