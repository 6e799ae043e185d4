"""Dataset formats and their checker: LeRobot v3.0 and HDF5 runs, `dataset check` catching
broken datasets, discarded attempts, statistics and video joining."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from robofollow.cli import main
from robofollow.data import units
from robofollow.data.check import check
from robofollow.data.generate import WRITERS, generate
from robofollow.data.jobs import FORMATS, demo_seed, select_tasks
from robofollow.data.lerobot_v30 import file_groups
from robofollow.data.stats import aggregate, array_stats
from robofollow.data.units import Options
from robofollow.resources import builtin_specs
from robofollow.sim.rollout import ExpertRunner
from robofollow.sim.video import VideoEncoder, concatenate, probe, read_frames
from tests.sim_helpers import benchmark

TASK = "pickup_yellow_block_1_left"


def _generate(out: Path, fmt: str, per_task: int = 2, instructions: str = "sample"):
    options = Options(fmt, per_task, (TASK,), 64, 48, instructions, benchmark().spec.digest)
    return generate(benchmark(), out, options, progress=False)


@pytest.fixture(scope="module")
def v21(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("v21") / "demos"
    _generate(out, "lerobot-v2.1")
    return out


@pytest.fixture(scope="module")
def v30(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("v30") / "demos"
    _generate(out, "lerobot-v3.0", instructions="all")
    return out


@pytest.mark.slow
def test_lerobot_v30_packs_episodes_into_files_and_validates(v30, v21):
    out = v30
    paraphrases = next(t.paraphrases for t in benchmark().spec.tasks if t.label == TASK)
    assert json.loads((out / "manifest.json").read_text())["episodes"] == 2 * len(paraphrases)
    report = check(out)
    assert report.ok, report.errors
    rows = pq.read_table(out / "meta/episodes/chunk-000/file-000.parquet").to_pylist()
    assert [r["tasks"][0] for r in rows[:len(paraphrases)]] == list(paraphrases)
    # every paraphrase of a demonstration is the same trajectory, back to back in one file
    key = "observation.images.cam_high"
    assert rows[1][f"videos/{key}/from_timestamp"] == pytest.approx(rows[0]["length"] / 25)
    frames = read_frames(out / f"videos/{key}/chunk-000/file-000.mp4")
    assert len(frames) == sum(r["length"] for r in rows)
    single = read_frames(v21 / f"videos/chunk-000/{key}/episode_000000.mp4")
    assert all(np.array_equal(a, b) for a, b in zip(frames[rows[0]["length"]:], single, strict=False))
    tasks = pq.read_table(out / "meta/tasks.parquet")
    assert json.loads(tasks.schema.metadata[b"pandas"])["index_columns"] == ["task"]
    assert tasks.column("task").to_pylist() == list(paraphrases)
    stats = json.loads((out / "meta/stats.json").read_text())
    assert stats["action"]["count"] == [sum(r["length"] for r in rows)]
    assert np.shape(stats[key]["mean"]) == (3, 1, 1)


@pytest.mark.slow
def test_hdf5_holds_raw_arrays_and_the_same_trajectories(tmp_path, v21):
    out = tmp_path / "h5"
    _generate(out, "hdf5")
    report = check(out)
    assert report.ok, report.errors
    with h5py.File(out / "data/episode_000001.hdf5", "r") as h5:
        action, images = h5["action"][()], h5["observations/images/cam_high"]
        assert images.dtype == np.uint8 and images.shape == (len(action), 48, 64, 3)
        assert h5.attrs["seed"] == demo_seed(1, 0) and h5.attrs["label"] == TASK
        state = h5["observations/qpos"][()]
    table = pq.read_table(v21 / "data/chunk-000/episode_000001.parquet")
    np.testing.assert_array_equal(np.array(table.column("action").to_pylist(), np.float32),
                                  action)
    np.testing.assert_array_equal(
        np.array(table.column("observation.state").to_pylist(), np.float32), state)


def _broken(v21: Path, tmp_path: Path) -> Path:
    copy = tmp_path / "copy"
    shutil.copytree(v21, copy)
    return copy


def _edit_parquet(path: Path, column: str, values) -> None:
    table = pq.read_table(path)
    index = table.column_names.index(column)
    table = table.set_column(index, column, pa.array(values, table.schema.field(column).type))
    pq.write_table(table, path)


@pytest.mark.slow
@pytest.mark.parametrize("damage, finding", [
    ("missing video", "missing video episode_000001.mp4"),
    ("frame index", "frame_index is not 0, 1, ... in order"),
    ("fps", "timestamp is not frame_index / fps"),
    ("fps", "video runs at 25 frames/s, the dataset at 30"),
    ("statistics", "observation.state mean does not match the frames"),
    ("short video", "video has 5 frames"),
    ("total", "total_frames is"),
    ("task", "are not one task of tasks.jsonl"),
])
def test_dataset_check_reports_what_is_wrong_and_where(v21, tmp_path, damage, finding):
    root = _broken(v21, tmp_path)
    info_path, meta = root / "meta/info.json", root / "meta"
    info = json.loads(info_path.read_text())
    data = root / "data/chunk-000/episode_000001.parquet"
    video = root / "videos/chunk-000/observation.images.cam_left_wrist/episode_000001.mp4"
    if damage == "missing video":
        video.unlink()
    elif damage == "frame index":
        frames = pq.read_table(data).column("frame_index").to_pylist()
        _edit_parquet(data, "frame_index", frames[::-1])
    elif damage == "fps":
        info["fps"] = 30
    elif damage == "statistics":
        lines = (meta / "episodes_stats.jsonl").read_text().splitlines()
        record = json.loads(lines[1])
        record["stats"]["observation.state"]["mean"][0] += 0.1
        lines[1] = json.dumps(record)
        (meta / "episodes_stats.jsonl").write_text("\n".join(lines) + "\n")
    elif damage == "short video":
        encoder = VideoEncoder(video, 64, 48, 25)
        for frame in read_frames(video)[:5]:
            encoder.add(frame)
        encoder.close()
    elif damage == "total":
        info["total_frames"] += 1
    elif damage == "task":
        lines = (meta / "episodes.jsonl").read_text().splitlines()
        lines[0] = json.dumps(dict(json.loads(lines[0]), tasks=["Dance."]))
        (meta / "episodes.jsonl").write_text("\n".join(lines) + "\n")
    info_path.write_text(json.dumps(info))
    report = check(root)
    assert not report.ok
    assert any(finding in error for error in report.errors), report.errors


@pytest.mark.slow
@pytest.mark.parametrize("field, change, finding", [
    ("videos/observation.images.cam_high/from_timestamp", 0.2, "video frames in"),
    ("dataset_from_index", 1, ", expected "),  # "frames 135..268, expected 134..268"
    ("length", 1, "total_frames is"),
])
def test_dataset_check_reports_a_broken_v30_episode_table(v30, tmp_path, field, change,
                                                          finding):
    root = tmp_path / "copy"
    shutil.copytree(v30, root)
    path = root / "meta/episodes/chunk-000/file-000.parquet"
    rows = pq.read_table(path).to_pylist()
    rows[1][field] += change
    pq.write_table(pa.Table.from_pylist(rows), path)
    report = check(root)
    assert any(finding in error for error in report.errors), report.errors


def test_dataset_check_on_a_folder_that_is_no_dataset(tmp_path):
    report = check(tmp_path)
    assert report.errors == [f"{tmp_path}: no meta/info.json (LeRobot) or info.json (HDF5): "
                             "not a dataset"]


@pytest.mark.slow
def test_rejected_attempts_are_discarded_recorded_and_the_next_seed_tried(tmp_path,
                                                                          monkeypatch):
    real = ExpertRunner.run
    calls = []

    def first_attempt_fails(self, compiled, episode, on_images=None):
        run = real(self, compiled, episode, on_images)
        calls.append(episode.seed)
        if episode.seed == demo_seed(0, 0):
            run.score = run.score.model_copy(update={"complete": False})
        return run

    monkeypatch.setattr(ExpertRunner, "run", first_attempt_fails)
    result = _generate(tmp_path / "demos", "lerobot-v2.1", per_task=1)
    assert calls == [demo_seed(0, 0), demo_seed(0, 1)]
    assert result.discarded == 1 and result.episodes == 1
    manifest = json.loads((tmp_path / "demos/manifest.json").read_text())
    [demo] = manifest["demos"]
    assert demo["seed"] == demo_seed(0, 1)
    assert demo["discarded"][0]["seed"] == demo_seed(0, 0)
    assert "incomplete" in demo["discarded"][0]["reason"]


@pytest.mark.slow
def test_a_task_without_any_complete_attempt_is_reported_not_hidden(tmp_path, monkeypatch):
    real = ExpertRunner.run

    def never(self, compiled, episode, on_images=None):
        run = real(self, compiled, episode, on_images)
        run.score = run.score.model_copy(update={"complete": False})
        return run

    monkeypatch.setattr(ExpertRunner, "run", never)
    monkeypatch.setattr(units, "MAX_ATTEMPTS", 2)
    result = _generate(tmp_path / "demos", "lerobot-v2.1", per_task=1)
    assert result.episodes == 0
    assert result.failed[0]["job"] == f"{TASK}/0000"
    assert "no complete demonstration in 2 seeds" in result.failed[0]["failed"]


@given(arrays(np.float64, st.tuples(st.integers(2, 40), st.integers(1, 4)),
              elements=st.floats(-1e3, 1e3)), st.integers(1, 39))
def test_aggregated_statistics_equal_the_statistics_of_the_whole(values, cut):
    cut = min(cut, len(values) - 1)
    whole = array_stats(values)
    merged = aggregate([array_stats(values[:cut]), array_stats(values[cut:])])
    for key in ("min", "max", "mean", "std"):
        np.testing.assert_allclose(merged[key], whole[key], rtol=1e-7, atol=1e-6)
    assert merged["count"] == whole["count"] == [len(values)]


def test_every_format_the_command_offers_has_a_writer():
    assert tuple(WRITERS) == FORMATS


def test_file_groups_fill_files_up_to_the_limit_in_order():
    assert file_groups([4, 4, 4, 9, 1], 8) == [[0, 1], [2], [3], [4]]
    assert file_groups([], 8) == []


def test_joined_videos_keep_every_frame_in_order(tmp_path):
    parts, expected = [], []
    for k, count in enumerate((5, 7, 4)):
        path = tmp_path / f"part{k}.mp4"
        encoder = VideoEncoder(path, 32, 16, 25)
        for i in range(count):
            frame = np.full((16, 32, 3), 30 * k + 5 * i, np.uint8)
            encoder.add(frame)
        encoder.close()
        parts.append(path)
        expected += read_frames(path)
    concatenate(parts, tmp_path / "all.mp4")
    joined = read_frames(tmp_path / "all.mp4")
    assert len(joined) == 16 and all(np.array_equal(a, b) for a, b in zip(joined, expected, strict=True))
    assert probe(tmp_path / "all.mp4").times == pytest.approx([i / 25 for i in range(16)])


def test_tasks_are_chosen_by_label_or_scene_and_a_typo_gets_suggestions(tmp_path, capsys):
    compiled = benchmark()
    chosen = select_tasks(compiled, ["pickup_left_cube", "scene1"])
    scene1 = [t.label for t in compiled.spec.tasks if t.scene == "scene1"]
    assert chosen == scene1 + ["pickup_left_cube"]  # spec order, not the order asked
    assert select_tasks(compiled, []) == [t.label for t in compiled.spec.tasks]
    assert main(["generate", str(builtin_specs()), "--out", str(tmp_path / "d"), "--tasks",
                 "pickup_left_cub", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "'pickup_left_cub' is neither a training task label nor a scene" in err
    assert "did you mean pickup_left_cube" in err and "Traceback" not in err
    assert not (tmp_path / "d").exists()
