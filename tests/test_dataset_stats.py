"""Feature statistics with LeRobot's quantiles (q01, q10, q50, q90, q99): the per-episode
histogram estimate against numpy, the images' exact quantiles from pixel-value counts,
LeRobot's aggregation over episodes, the statistics files of a written dataset (v2.1 and v3.0)
and `dataset check` on them (quantiles required in v3.0, optional in v2.1)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from robofollow.data import lerobot_v21, lerobot_v30
from robofollow.data.check import check
from robofollow.data.check_parts import QUANTILE_NOTE
from robofollow.data.jobs import demo_jobs
from robofollow.data.lerobot import VIDEO_KEYS, vectors
from robofollow.data.sinks import STATS_EVERY, ImageStats
from robofollow.data.stats import (
    BINS,
    PADDING,
    QUANTILE_KEYS,
    QUANTILES,
    aggregate,
    array_stats,
    as_image_stats,
    counted_quantiles,
)
from robofollow.data.units import Options, UnitRecorder, unit_path
from tests.sim_helpers import benchmark

TASK = "pickup_yellow_block_1_left"
SAMPLES = arrays(np.float64, st.tuples(st.integers(2, 300), st.integers(1, 4)),
                 elements=st.floats(-1e3, 1e3))


def _bin_width(values: np.ndarray) -> np.ndarray:
    """LeRobot's histogram bin width per dimension: the quantiles' resolution."""
    return (values.max(0) - values.min(0) + 2 * PADDING) / BINS


@given(SAMPLES)
def test_quantiles_are_within_one_histogram_bin_of_numpy(values):
    """Tolerance: one bin width ((max - min) / 5000) plus float rounding; the histogram's
    estimate targets numpy's inverted-CDF quantile (the smallest value with at least q * N
    values at or below it)."""
    stats = array_stats(values)
    expected = np.quantile(values, QUANTILES, axis=0, method="inverted_cdf")
    for key, want in zip(QUANTILE_KEYS, expected, strict=True):
        assert np.all(np.abs(np.array(stats[key]) - want) <= _bin_width(values) + 1e-9), key
    ordered = np.array([stats[k] for k in ("min", *QUANTILE_KEYS, "max")])
    assert np.all(np.diff(ordered, axis=0) >= -2 * PADDING)  # bins start at min - PADDING


def test_quantiles_of_a_fine_sample_match_numpy_closely():
    values = np.random.default_rng(0).normal(size=(20_000, 3))
    stats = array_stats(values)
    for key, want in zip(QUANTILE_KEYS, np.quantile(values, QUANTILES, axis=0), strict=True):
        np.testing.assert_allclose(stats[key], want, atol=_bin_width(values).max())


def test_a_single_value_has_its_mean_for_every_quantile_as_in_lerobot():
    stats = array_stats(np.array([[0.5, -2.0]]))
    assert all(stats[key] == [0.5, -2.0] for key in QUANTILE_KEYS)
    assert stats["count"] == [1]


@given(arrays(np.int64, st.tuples(st.integers(1, 3), st.integers(1, 256)),
              elements=st.sampled_from([0, 0, 1, 2, 7, 1000]))
       .filter(lambda counts: np.all(counts.sum(-1) > 0)))
def test_counted_quantiles_are_numpys_inverted_cdf_of_the_counted_sample(counts):
    """Exact, with no sample materialised: the value numpy.quantile(..., "inverted_cdf")
    returns for the sample the counts describe (value i repeated counts[i] times)."""
    got = counted_quantiles(counts)
    assert got.shape == (len(QUANTILES), len(counts))
    for row, column in zip(counts, got.T, strict=True):
        sample = np.repeat(np.arange(len(row)), row)
        assert column.tolist() == np.quantile(sample, QUANTILES, method="inverted_cdf").tolist()


def test_image_quantiles_are_exact_over_the_sampled_pixels():
    """ImageStats: per channel, numpy's inverted-CDF quantiles of the pixels its statistics
    sample (every STATS_EVERY-th frame, subsampled by its stride), scaled to [0, 1]; LeRobot's
    histogram estimate of the same pixels is within one of its bins of them."""
    rng = np.random.default_rng(3)
    frames = [np.clip(rng.normal((60, 128, 200), (30, 50, 20), (48, 64, 3)), 0, 255)
              .astype(np.uint8) for _ in range(9)]
    stats = ImageStats(64, 48)
    for frame in frames:
        stats.add(frame)
    result = stats.result()
    pixels = np.concatenate([f[::stats.stride, ::stats.stride].reshape(-1, 3)
                             for f in frames[::STATS_EVERY]])
    exact = np.quantile(pixels, QUANTILES, axis=0, method="inverted_cdf") / 255.0
    assert result["count"] == len(frames[::STATS_EVERY])
    for key, want in zip(QUANTILE_KEYS, exact, strict=True):
        assert result[key] == want.tolist(), key
        lerobot = array_stats(pixels)[key]  # the histogram method, on the raw values
        assert np.all(np.abs(np.array(lerobot) / 255.0 - want) <= 1 / BINS + 1e-12), key
    assert np.allclose(result["mean"], pixels.mean(0) / 255.0)
    image = as_image_stats(result)
    ordered = np.array([image[k] for k in ("min", *QUANTILE_KEYS, "max")])
    assert ordered.shape == (7, 3, 1, 1) and np.all(np.diff(ordered, axis=0) >= 0)


@given(st.lists(SAMPLES.filter(lambda v: v.shape[1] == 2), min_size=1, max_size=4))
def test_aggregated_quantiles_are_lerobots_conservative_envelope(episodes):
    """LeRobot (compute_stats.aggregate_feature_stats): the smallest episode estimate for
    q01..q50, the largest for q90, q99. These bound the quantiles of the whole."""
    stats = [array_stats(e) for e in episodes]
    merged = aggregate(stats)
    for q, key in zip(QUANTILES, QUANTILE_KEYS, strict=True):
        bound = np.min if q <= 0.5 else np.max
        assert merged[key] == bound([s[key] for s in stats], axis=0).tolist()
    whole = np.concatenate(episodes)
    exact = np.quantile(whole, QUANTILES, axis=0, method="inverted_cdf")
    slack = max(_bin_width(e).max() for e in episodes) + 1e-9
    for q, key, value in zip(QUANTILES, QUANTILE_KEYS, exact, strict=True):
        bounded = np.array(merged[key])
        assert np.all(bounded <= value + slack if q <= 0.5 else bounded >= value - slack), key


def test_quantiles_missing_in_an_episode_are_left_out_of_the_aggregate():
    images = [as_image_stats({"min": [0.0] * 3, "max": [1.0] * 3, "mean": [0.5] * 3,
                              "std": [0.1] * 3, "count": 4, **extra})
              for extra in ({"q50": [0.4] * 3}, {})]
    assert np.shape(images[0]["q50"]) == (3, 1, 1) and images[0]["count"] == [4]
    merged = aggregate(images)
    assert "q50" not in merged and np.shape(merged["mean"]) == (3, 1, 1)


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> dict[str, Path]:
    """One recorded demonstration (every paraphrase an episode) written as v2.1 and v3.0."""
    work = tmp_path_factory.mktemp("units")
    compiled = benchmark()
    options = Options("lerobot-v3.0", 1, (TASK,), 64, 48, "all", compiled.spec.digest)
    job = demo_jobs(compiled, 1, [TASK], "all")[0]
    recorder = UnitRecorder(compiled, options, work)
    try:
        demos = [(recorder.record(job), unit_path(work, job))]
    finally:
        recorder.close()
    roots = {}
    for name, writer in (("v2.1", lerobot_v21.write), ("v3.0", lerobot_v30.write)):
        roots[name] = tmp_path_factory.mktemp(name)
        writer(roots[name], demos, options.width, options.height)
    return roots


def _frames(root: Path, index: int) -> dict[str, np.ndarray]:
    table = pq.read_table(root / lerobot_v21.DATA_PATH.format(episode_chunk=0,
                                                              episode_index=index))
    return {key: vectors(table.column(key)) for key in ("observation.state", "action")}


@pytest.mark.slow
def test_v21_episode_statistics_hold_the_quantiles_of_the_frames(written):
    root = written["v2.1"]
    records = [json.loads(line) for line in
               (root / "meta/episodes_stats.jsonl").read_text().splitlines()]
    assert len(records) > 1
    for record in records:
        for key, values in _frames(root, record["episode_index"]).items():
            expected = array_stats(values)
            assert all(record["stats"][key][q] == expected[q] for q in QUANTILE_KEYS)
        for key in VIDEO_KEYS:  # the images' own quantiles, per channel
            assert all(np.shape(record["stats"][key][q]) == (3, 1, 1) for q in QUANTILE_KEYS)
    assert check(root).ok, check(root).errors


@pytest.mark.slow
def test_v30_statistics_hold_per_episode_and_aggregated_quantiles(written):
    root = written["v3.0"]
    rows = pq.read_table(root / "meta/episodes/chunk-000/file-000.parquet").to_pylist()
    stats = json.loads((root / "meta/stats.json").read_text())
    for key in ("observation.state", "action"):
        episodes = [{name: row[f"stats/{key}/{name}"] for name in
                     ("min", "max", "mean", "std", "count", *QUANTILE_KEYS)} for row in rows]
        assert all(len(e[q]) == 14 for e in episodes for q in QUANTILE_KEYS)
        assert {q: stats[key][q] for q in QUANTILE_KEYS} == {
            q: aggregate(episodes)[q] for q in QUANTILE_KEYS}
    for key in VIDEO_KEYS:  # per-channel, 3 x 1 x 1 values in [0, 1], aggregated alike
        episodes = [{name: row[f"stats/{key}/{name}"] for name in
                     ("min", "max", "mean", "std", "count", *QUANTILE_KEYS)} for row in rows]
        assert all(np.shape(e[q]) == (3, 1, 1) for e in episodes for q in QUANTILE_KEYS)
        merged = aggregate(episodes)
        assert {q: stats[key][q] for q in QUANTILE_KEYS} == {q: merged[q] for q in QUANTILE_KEYS}
        values = np.array([stats[key][k] for k in ("min", *QUANTILE_KEYS, "max")])
        assert np.all(np.diff(values, axis=0) >= 0) and 0 <= values.min() <= values.max() <= 1
    assert check(root).ok, check(root).errors


def _damaged_v21(written, tmp_path: Path, change) -> list[str]:
    root = tmp_path / "copy"
    shutil.copytree(written["v2.1"], root)
    path = root / "meta/episodes_stats.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()]
    change(records[0]["stats"]["action"])
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    return check(root).errors


@pytest.mark.slow
@pytest.mark.parametrize("damage, finding", [
    (lambda s: s.pop("q50"), "episode 0: action statistics lack ['q50']"),
    (lambda s: s.update(q10=s["q90"], q90=s["q10"]),
     "episode 0: action statistics are not ordered min <= q01 <= q10"),
    (lambda s: s.update(q50=[(a + b) / 2 for a, b in zip(s["q50"], s["q90"], strict=True)]),
     "episode 0: action q50 does not match the frames"),
    (lambda s: s.update(q99=s["q99"][:3]), "episode 0: action statistics must be 14 values"),
], ids=["q50 missing", "q10 and q90 swapped", "q50 off", "q99 too short"])
def test_dataset_check_finds_missing_disordered_or_wrong_quantiles(written, tmp_path, damage,
                                                                   finding):
    errors = _damaged_v21(written, tmp_path, damage)
    assert any(finding in error for error in errors), errors


@pytest.mark.slow
def test_dataset_check_finds_disordered_quantiles_in_v30_stats_json(written, tmp_path):
    root = tmp_path / "copy"
    shutil.copytree(written["v3.0"], root)
    path = root / "meta/stats.json"
    stats = json.loads(path.read_text())
    stats["observation.state"]["q01"] = stats["observation.state"]["q99"]
    path.write_text(json.dumps(stats))
    assert check(root).errors == [("meta/stats.json: observation.state statistics are not "
                                   "ordered min <= q01 <= q10 <= q50 <= q90 <= q99 <= max")]


def _without_quantiles(stats: dict, features=None) -> None:
    """Drop the quantiles of `features` (all) from one {feature: {stat: value}} record."""
    for feature in features or stats:
        for key in QUANTILE_KEYS:
            stats[feature].pop(key, None)


@pytest.mark.slow
def test_a_v21_dataset_without_quantiles_as_lerobot_03_wrote_them_validates(written, tmp_path):
    """LeRobot 0.3.x wrote v2.1 episode statistics with no quantiles (state, action, images):
    `dataset check` accepts them, still comparing min, max, mean, std and count."""
    root = tmp_path / "copy"
    shutil.copytree(written["v2.1"], root)
    path = root / "meta/episodes_stats.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()]
    for record in records:
        _without_quantiles(record["stats"])
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    assert "q50" not in path.read_text()
    report = check(root)
    assert report.ok, report.errors
    records[0]["stats"]["action"]["mean"][0] += 0.1  # the rest is still compared
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    assert check(root).errors == ["episode 0: action mean does not match the frames"]


def _v30_without_quantiles(written, tmp_path: Path, features=None):
    """The check's report on a copy of the v3.0 dataset whose episode table and stats.json lack
    the quantiles of `features` (all)."""
    root = tmp_path / "copy"
    shutil.copytree(written["v3.0"], root)
    path = root / "meta/episodes/chunk-000/file-000.parquet"
    table = pq.read_table(path)
    dropped = [c for c in table.column_names if c.startswith("stats/")
               and c.split("/")[2] in QUANTILE_KEYS
               and (features is None or c.split("/")[1] in features)]
    pq.write_table(table.drop_columns(dropped), path)
    stats = json.loads((root / "meta/stats.json").read_text())
    _without_quantiles(stats, features)
    (root / "meta/stats.json").write_text(json.dumps(stats))
    return check(root)


@pytest.mark.slow
@pytest.mark.parametrize("features", [None, ["observation.images.cam_high"]],
                         ids=["all", "one-camera"])
def test_a_v30_dataset_without_quantiles_passes_with_a_note(written, tmp_path, features):
    """As LeRobot's v2.1 -> v3.0 converter leaves a dataset: loadable, but not for policies
    that normalise by quantiles."""
    report = _v30_without_quantiles(written, tmp_path, features)
    assert report.ok, report.errors
    assert report.notes == [QUANTILE_NOTE]
    assert "augment_dataset_quantile_stats" in report.render()


@pytest.mark.slow
def test_a_null_quantile_in_the_v30_episode_table_is_a_missing_one(written, tmp_path):
    """Episodes whose statistics differ in keys leave nulls in the table's other rows."""
    root = tmp_path / "copy"
    shutil.copytree(written["v3.0"], root)
    path = root / "meta/episodes/chunk-000/file-000.parquet"
    table = pq.read_table(path)
    name = "stats/observation.images.cam_high/q50"
    column = table.column(name).to_pylist()
    column[1] = None
    table = table.set_column(table.column_names.index(name), name,
                             pa.array(column, table.schema.field(name).type))
    pq.write_table(table, path)
    assert check(root).errors == [
        "episode 1: observation.images.cam_high statistics lack ['q50']"]
