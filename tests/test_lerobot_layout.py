"""The layout LeRobot relies on when it loads a dataset `robofollow generate` wrote, checked
without LeRobot (CI cannot install it: torch, torchcodec, datasets): every assertion restates
what LeRobot's loading code does at that point and cites it.

v3.0 follows lerobot 0.4.4 (`lerobot/datasets/lerobot_dataset.py`: LeRobotDatasetMetadata,
LeRobotDataset; `utils.py`: load_info, load_tasks, load_episodes, load_nested_dataset,
get_hf_features_from_features, dataset_to_policy_features, check_version_compatibility;
`video_utils.py`: decode_video_frames; `compute_stats.py`: aggregate_stats;
`processor/normalize_processor.py`; `sampler.py`: EpisodeAwareSampler). v2.1 follows lerobot
0.3.3, the last release that reads it, and openpi, which pins a v2.1 LeRobot (load_tasks,
load_episodes, load_episodes_stats, get_episode_data_index, check_timestamps_sync).

Checked by hand against the real packages (lerobot 0.4.4 / 0.3.3, offline): both datasets load,
every frame of every episode decodes to the frame at its place in the mp4, and `lerobot-train`
runs ACT and diffusion on them."""

from __future__ import annotations

import json
from itertools import pairwise
from pathlib import Path

import av
import numpy as np
import pyarrow.parquet as pq
import pytest

from robofollow.data.generate import generate
from robofollow.data.units import Options
from tests.sim_helpers import benchmark

TASK = "pickup_yellow_block_1_left"
# LeRobot's DEFAULT_FEATURES: the bookkeeping columns every dataset has, with these dtypes/shapes
DEFAULT_FEATURES = {"timestamp": "float32", "frame_index": "int64", "episode_index": "int64",
                    "index": "int64", "task_index": "int64"}
TOLERANCE_S = 1e-4  # LeRobotDataset(tolerance_s=1e-4), lerobot-train's default too
QUANTILE_KEYS = ("q01", "q10", "q50", "q90", "q99")  # compute_stats.DEFAULT_QUANTILES
# hf dtype -> the Arrow type datasets.Value(dtype) casts the column to
ARROW = {"float32": "float", "int64": "int64"}


def _generate(out: Path, fmt: str) -> Path:
    # one demonstration read as each of its paraphrases: several episodes back to back in one
    # v3.0 file, so the per-episode offsets (from_timestamp, dataset_from_index) are not all 0
    options = Options(fmt, 1, (TASK,), 64, 48, "all", benchmark().spec.digest)
    generate(benchmark(), out, options, progress=False)
    return out


@pytest.fixture(scope="module")
def v30(tmp_path_factory) -> Path:
    return _generate(tmp_path_factory.mktemp("lerobot") / "demos", "lerobot-v3.0")


@pytest.fixture(scope="module")
def v21(tmp_path_factory) -> Path:
    return _generate(tmp_path_factory.mktemp("lerobot") / "demos", "lerobot-v2.1")


def _info(root: Path) -> dict:
    return json.loads((root / "meta/info.json").read_text())


def _rows(path: Path) -> list[dict]:
    return pq.read_table(path).to_pylist()


def _jsonl(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _video_timestamps(path: Path) -> tuple[np.ndarray, tuple[int, int], float]:
    """Presentation times (s) of every frame, (height, width), frame rate; demuxed, no decoding."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        pts = sorted(float(p.pts * stream.time_base) for p in container.demux(stream)
                     if p.pts is not None)
        return np.array(pts), (stream.height, stream.width), float(stream.average_rate)


def _data_frames(root: Path, pattern: str) -> list[dict]:
    """The frames in the order LeRobot concatenates the data files (sorted paths)."""
    return [row for path in sorted((root / "data").glob(pattern)) for row in _rows(path)]


def _check_features(info: dict) -> None:
    features = info["features"]
    for name, feature in features.items():
        # load_info turns every feature's "shape" into a tuple: dtype, shape, names all present
        assert {"dtype", "shape", "names"} <= set(feature), name
        # _validate_feature_names: no "/" in a feature name (it separates flattened stats keys)
        assert "/" not in name
    # DEFAULT_FEATURES: the bookkeeping features, shape (1,) -> datasets.Value(dtype)
    for name, dtype in DEFAULT_FEATURES.items():
        assert features[name]["dtype"] == dtype and features[name]["shape"] == [1], name
    # dataset_to_policy_features: "observation.*" is a STATE input, "action" the ACTION target;
    # 1-D shapes become datasets.Sequence(length=shape[0])
    for name in ("observation.state", "action"):
        assert features[name]["dtype"] == "float32" and features[name]["shape"] == [14]
        assert len(features[name]["names"]) == 14
    cameras = [k for k, f in features.items() if f["dtype"] == "video"]
    assert cameras == [f"observation.images.{c}" for c in
                       ("cam_high", "cam_left_wrist", "cam_right_wrist")]
    for key in cameras:
        # dataset_to_policy_features: a visual feature must be 3-D, and only names[2] in
        # ("channel", "channels") makes it permute (h, w, c) to the (c, h, w) the decoder returns
        assert features[key]["shape"] == [48, 64, 3]
        assert features[key]["names"] == ["height", "width", "channels"]


def _check_data_columns(info: dict, frames_table_names: list[str]) -> None:
    # load_nested_dataset -> Dataset.from_parquet(features=get_hf_features_from_features(...)):
    # one column per non-video feature and no other (an extra column fails the load, a missing
    # one comes back as None)
    expected = [k for k, f in info["features"].items() if f["dtype"] != "video"]
    assert sorted(frames_table_names) == sorted(expected)


def _check_frame_types(path: Path, info: dict) -> None:
    schema = pq.read_schema(path)
    for name in DEFAULT_FEATURES:
        assert str(schema.field(name).type) == ARROW[info["features"][name]["dtype"]], name
    for name in ("observation.state", "action"):
        # datasets.Sequence(length=14, Value("float32")): 14 float32 per frame
        assert str(schema.field(name).type.value_type) == "float"
        assert all(len(v) == 14 for v in pq.read_table(path, columns=[name])[name].to_pylist())


def _check_timestamps(frames: list[dict], fps: int) -> None:
    """Within an episode frame_index runs 0, 1, ... and timestamp = frame_index / fps."""
    starts = {}
    for row in frames:
        starts.setdefault(row["episode_index"], row["index"])
        assert row["frame_index"] == row["index"] - starts[row["episode_index"]]
        # the video frame LeRobot decodes for a row is the one within tolerance_s of (the
        # episode's offset +) its timestamp: FrameTimestampError otherwise; v2.1's
        # check_timestamps_sync also wants consecutive timestamps 1/fps +/- tolerance_s apart
        assert abs(row["timestamp"] - row["frame_index"] / fps) < TOLERANCE_S / 10


def _check_stats(stats: dict, info: dict) -> None:
    """meta/stats.json (v3.0) or one episode's stats (v2.1): what LeRobot's normalisers read."""
    features = info["features"]
    assert set(stats) == set(features)  # every feature has statistics (LeRobot writes them all)
    for key, feature_stats in stats.items():
        values = {k: np.asarray(v, dtype=np.float64) for k, v in feature_stats.items()}
        # cast_stats_to_numpy / aggregate_stats' _validate_stat_value: numeric arrays, ndim >= 1,
        # count of shape (1,), and for a camera every other statistic of shape (3, 1, 1)
        assert values["count"].shape == (1,) and values["count"][0] > 0, key
        expected = (3, 1, 1) if features[key]["dtype"] == "video" else tuple(features[key]["shape"])
        for name in ("min", "max", "mean", "std", *QUANTILE_KEYS):
            # normalize_processor: MEAN_STD reads mean/std, MIN_MAX min/max, QUANTILES q01/q99
            # (π0 / π0.5's state and action), QUANTILE10 q10/q90; a missing one is a ValueError
            # at the first batch ("QUANTILES normalization mode requires q01 and q99 stats")
            assert name in values, (key, name)
            assert values[name].shape == expected, (key, name, values[name].shape)
            assert np.isfinite(values[name]).all(), (key, name)
        # QUANTILES divides by q99 - q01 (LeRobot adds eps only where it is 0): ordered quantiles
        ordered = [values[k] for k in ("min", *QUANTILE_KEYS, "max")]
        assert all((a <= b + 1e-9).all() for a, b in pairwise(ordered)), key
        assert (values["std"] >= 0).all()


# ---------------------------------------------------------------------------- LeRobot v3.0


def test_v30_info_is_what_lerobot_0_4_reads(v30):
    info = _info(v30)
    # LeRobotDatasetMetadata.load_metadata -> check_version_compatibility: a major version
    # below the codebase's ("v3.0") raises BackwardCompatibilityError (the v2.1 -> v3.0
    # conversion message); the revision LeRobot asks the hub for is also "v3.0"
    assert info["codebase_version"] == "v3.0"
    # properties of LeRobotDatasetMetadata read straight from info.json (KeyError otherwise)
    for key in ("fps", "features", "data_path", "video_path", "robot_type", "total_episodes",
                "total_frames", "total_tasks", "chunks_size", "data_files_size_in_mb",
                "video_files_size_in_mb", "splits"):
        assert key in info, key
    assert info["fps"] == 25 and isinstance(info["fps"], int)
    # get_data_file_path / get_video_file_path: str.format with exactly these fields
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["video_path"] == \
        "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
    _check_features(info)


def test_v30_tasks_parquet_is_a_frame_indexed_by_the_task_strings(v30):
    table = pq.read_table(v30 / "meta/tasks.parquet")
    # load_tasks: pandas.read_parquet; the pandas metadata makes the task strings the index,
    # and __getitem__ answers item["task"] = tasks.iloc[task_index].name
    index_columns = json.loads(table.schema.metadata[b"pandas"])["index_columns"]
    assert len(index_columns) == 1
    tasks = table.column(index_columns[0]).to_pylist()
    # iloc is positional: row i must be task_index i
    assert table.column("task_index").to_pylist() == list(range(len(tasks)))
    # get_task_index looks a string up with .loc: each task once
    assert len(set(tasks)) == len(tasks) == _info(v30)["total_tasks"]


def test_v30_episodes_table_points_at_every_frame_and_video_segment(v30):
    info, fps = _info(v30), _info(v30)["fps"]
    # load_episodes: every meta/episodes/*/*.parquet, "stats/..." columns dropped
    paths = sorted((v30 / "meta/episodes").glob("*/*.parquet"))
    episodes = [row for path in paths for row in _rows(path)]
    # meta.episodes[ep_idx] is positional: row i must be episode i (total_episodes of them)
    assert [e["episode_index"] for e in episodes] == list(range(info["total_episodes"]))
    cameras = [k for k, f in info["features"].items() if f["dtype"] == "video"]
    tasks = pq.read_table(v30 / "meta/tasks.parquet").column("task").to_pylist()
    frames = _data_frames(v30, "*/*.parquet")
    # hf_dataset[idx] is positional and delta-timestamp queries use the absolute "index":
    # with all episodes loaded, index must equal the row's place in the concatenated files
    assert [row["index"] for row in frames] == list(range(info["total_frames"]))
    videos: dict[Path, tuple] = {}
    previous_end = 0
    for e in episodes:
        start, end = e["dataset_from_index"], e["dataset_to_index"]
        # _get_query_indices clamps to [dataset_from_index, dataset_to_index) and pads outside;
        # EpisodeAwareSampler draws range(from, to - drop_n_last_frames): contiguous, in order
        assert start == previous_end and end - start == e["length"] > 0
        previous_end = end
        rows = frames[start:end]
        assert {r["episode_index"] for r in rows} == {e["episode_index"]}
        # the episode's tasks are the strings its frames' task_index name
        assert sorted({tasks[r["task_index"]] for r in rows}) == sorted(e["tasks"])
        # get_data_file_path: info["data_path"] with the row's data/chunk_index, file_index;
        # a missing file makes LeRobot try to download it from the hub
        data = v30 / info["data_path"].format(chunk_index=e["data/chunk_index"],
                                              file_index=e["data/file_index"])
        assert data.is_file()
        assert {r["index"] for r in _rows(data)} >= set(range(start, end))
        for key in cameras:
            video = v30 / info["video_path"].format(
                video_key=key, chunk_index=e[f"videos/{key}/chunk_index"],
                file_index=e[f"videos/{key}/file_index"])
            assert video.is_file()  # _check_cached_episodes_sufficient, else a download
            if video not in videos:
                videos[video] = _video_timestamps(video)
            pts, size, rate = videos[video]
            assert size == (48, 64) and rate == fps
            # _query_videos decodes at from_timestamp + timestamp; decode_video_frames raises
            # FrameTimestampError unless a frame lies within tolerance_s of each query
            begin = e[f"videos/{key}/from_timestamp"]
            assert e[f"videos/{key}/to_timestamp"] == pytest.approx(begin + e["length"] / fps)
            queries = begin + np.array([r["timestamp"] for r in rows], dtype=np.float64)
            nearest = np.abs(pts[None, :] - queries[:, None]).min(1)
            assert (nearest < TOLERANCE_S).all(), (video, e["episode_index"])
            # and the frames in the file before this episode's are the earlier episodes' ones
            assert int(np.sum(pts < begin - TOLERANCE_S)) == sum(
                x["length"] for x in episodes[:e["episode_index"]]
                if x[f"videos/{key}/file_index"] == e[f"videos/{key}/file_index"]
                and x[f"videos/{key}/chunk_index"] == e[f"videos/{key}/chunk_index"])
    assert previous_end == info["total_frames"]


def test_v30_frames_have_lerobots_columns_types_and_timestamps(v30):
    info = _info(v30)
    paths = sorted((v30 / "data").glob("*/*.parquet"))
    assert paths  # load_nested_dataset: FileNotFoundError (then a hub download) without any
    for path in paths:
        _check_data_columns(info, pq.read_schema(path).names)
        _check_frame_types(path, info)
    frames = _data_frames(v30, "*/*.parquet")
    _check_timestamps(frames, info["fps"])
    assert {r["task_index"] for r in frames} <= set(range(info["total_tasks"]))


def test_v30_stats_json_has_every_statistic_the_normalisers_read(v30):
    # load_stats: meta/stats.json, nested dict of lists -> numpy arrays
    _check_stats(json.loads((v30 / "meta/stats.json").read_text()), _info(v30))


# ---------------------------------------------------------------------------- LeRobot v2.1


def test_v21_info_is_what_lerobot_0_3_and_openpi_read(v21):
    info = _info(v21)
    # lerobot 0.3.x: CODEBASE_VERSION "v2.1"; lerobot >= 0.4 refuses it (BackwardCompatibilityError:
    # convert with lerobot.datasets.v30.convert_dataset_v21_to_v30)
    assert info["codebase_version"] == "v2.1"
    for key in ("fps", "features", "data_path", "video_path", "robot_type", "total_episodes",
                "total_frames", "total_tasks", "total_chunks", "total_videos", "chunks_size",
                "splits"):
        assert key in info, key
    # get_data_file_path / get_video_file_path: episode_chunk = episode_index // chunks_size
    assert info["data_path"] == \
        "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
    assert info["video_path"] == \
        "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
    _check_features(info)


def test_v21_episodes_tasks_frames_and_videos_line_up(v21):
    info = _info(v21)
    fps = info["fps"]
    # load_tasks: {task_index: task} from meta/tasks.jsonl
    tasks = {t["task_index"]: t["task"] for t in _jsonl(v21 / "meta/tasks.jsonl")}
    assert sorted(tasks) == list(range(info["total_tasks"]))
    # load_episodes: meta/episodes.jsonl keyed by episode_index (sorted)
    episodes = sorted(_jsonl(v21 / "meta/episodes.jsonl"), key=lambda e: e["episode_index"])
    assert [e["episode_index"] for e in episodes] == list(range(info["total_episodes"]))
    # load_dataset("parquet", data_dir="data") reads the files in path order and
    # get_episode_data_index cuts the frames by the cumulative "length"s in episode order
    frames = _data_frames(v21, "*/episode_*.parquet")
    assert len(frames) == sum(e["length"] for e in episodes) == info["total_frames"]
    assert [r["index"] for r in frames] == list(range(info["total_frames"]))
    start = 0
    cameras = [k for k, f in info["features"].items() if f["dtype"] == "video"]
    for e in episodes:
        rows = frames[start:start + e["length"]]
        start += e["length"]
        assert {r["episode_index"] for r in rows} == {e["episode_index"]}
        assert sorted({tasks[r["task_index"]] for r in rows}) == sorted(e["tasks"])
        chunk = e["episode_index"] // info["chunks_size"]
        data = v21 / info["data_path"].format(episode_chunk=chunk,
                                              episode_index=e["episode_index"])
        _check_data_columns(info, pq.read_schema(data).names)
        _check_frame_types(data, info)
        for key in cameras:
            video = v21 / info["video_path"].format(episode_chunk=chunk, video_key=key,
                                                    episode_index=e["episode_index"])
            pts, size, rate = _video_timestamps(video)
            assert size == (48, 64) and rate == fps and len(pts) == e["length"]
            # one episode per file, starting at 0: frame i at i / fps (decode_video_frames)
            queries = np.array([r["timestamp"] for r in rows], dtype=np.float64)
            assert (np.abs(pts - queries) < TOLERANCE_S).all()
    _check_timestamps(frames, fps)


def test_v21_episode_stats_are_what_lerobot_aggregates(v21):
    info = _info(v21)
    # load_episodes_stats: {"episode_index", "stats"} per line, one per episode; LeRobot 0.3
    # aggregates them into meta.stats (aggregate_stats validates the shapes)
    lines = _jsonl(v21 / "meta/episodes_stats.jsonl")
    assert sorted(line["episode_index"] for line in lines) == list(range(info["total_episodes"]))
    for line in lines:
        _check_stats(line["stats"], info)
