"""Feature statistics as LeRobot stores them, per episode and aggregated over episodes: min,
max, mean, std (population), count and the quantiles q01, q10, q50, q90, q99, each per
dimension (LeRobot's src/lerobot/datasets/compute_stats.py)."""

from __future__ import annotations

import numpy as np

QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)
QUANTILE_KEYS = tuple(f"q{round(q * 100):02d}" for q in QUANTILES)
BINS = 5000  # LeRobot's histogram resolution for quantiles
PADDING = 1e-10  # its histogram overhangs [min, max] by this much on each side


def _first_reaching(cumulative: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each of QUANTILES falls in cumulative counts [..., K] (a running total along the
    last axis): (its target q * total, the first index whose cumulative count reaches it),
    each [..., len(QUANTILES)]. Over the counts of distinct sorted values, that index is the
    value numpy.quantile(..., method="inverted_cdf") returns: the smallest with at least
    q * total values at or below it."""
    targets = np.multiply.outer(cumulative[..., -1], QUANTILES)
    reached = (cumulative[..., None, :] < targets[..., None]).sum(-1)
    return targets, reached


def quantiles(values: np.ndarray) -> np.ndarray:
    """LeRobot's quantile estimates (RunningQuantileStats) of a 1-D sample of at least two
    values, one per QUANTILES: a histogram of BINS equal bins over [min - PADDING, max +
    PADDING]; quantile q lies in the first bin whose cumulative count reaches q * count, read
    by linear interpolation inside it (its left edge for the first bin). The result is within
    one bin width of numpy.quantile(values, q, method="inverted_cdf")."""
    edges = np.linspace(values.min() - PADDING, values.max() + PADDING, BINS + 1)
    cumulative = np.cumsum(np.histogram(values, edges)[0])
    targets, bins = _first_reaching(cumulative)  # < BINS: the last cumulative count is len
    before = np.where(bins > 0, cumulative[bins - 1], 0)
    inside = edges[bins] + (targets - before) / (cumulative[bins] - before) * np.diff(edges)[bins]
    return np.where(bins > 0, inside, edges[0])


def counted_quantiles(counts: np.ndarray) -> np.ndarray:
    """Exact quantiles of a sample of the integers 0 .. K - 1 given by how often each occurs
    (counts [..., K], e.g. [channels, 256] for uint8 pixels), as [len(QUANTILES), ...]: per
    QUANTILES, the smallest value with at least q * total values at or below it, which is
    numpy.quantile(np.repeat(np.arange(K), counts), q, method="inverted_cdf") read off the
    cumulative counts without materialising the sample. `quantiles` (LeRobot's histogram
    method) estimates the same quantile to within one of its bins."""
    _, reached = _first_reaching(np.cumsum(counts, axis=-1))
    return np.moveaxis(reached, -1, 0).astype(np.float64)


def array_stats(values: np.ndarray) -> dict[str, list]:
    """Statistics over the first axis of a (N,) or (N, D) array, in float64; as in LeRobot, the
    quantiles of fewer than two values are the mean."""
    values = np.asarray(values, dtype=np.float64)
    values = values.reshape(len(values), -1)
    mean = values.mean(0)
    estimates = (np.array([quantiles(column) for column in values.T]).T if len(values) > 1
                 else np.tile(mean, (len(QUANTILES), 1)))
    return {"min": values.min(0).tolist(), "max": values.max(0).tolist(),
            "mean": mean.tolist(), "std": values.std(0).tolist(), "count": [len(values)],
            **dict(zip(QUANTILE_KEYS, estimates.tolist(), strict=True))}


def aggregate(stats: list[dict[str, list]]) -> dict[str, list]:
    """One feature's statistics over several episodes: count-weighted mean, pooled variance.
    Whole-dataset quantiles cannot be recovered from per-episode ones, so, as LeRobot's
    aggregate_feature_stats does (main since PR #3804; releases up to 0.6.1 took the
    count-weighted mean instead), each quantile that every episode has is bounded
    conservatively: the smallest episode value for q01..q50, the largest for q90 and q99."""
    counts = np.array([s["count"][0] for s in stats], dtype=np.float64)
    means = np.array([s["mean"] for s in stats], dtype=np.float64)
    variances = np.square(np.array([s["std"] for s in stats], dtype=np.float64))
    weights = (counts / counts.sum()).reshape((-1,) + (1,) * (means.ndim - 1))
    mean = (weights * means).sum(0)
    variance = (weights * (variances + np.square(means - mean))).sum(0)
    result = {"min": np.min([s["min"] for s in stats], axis=0).tolist(),
              "max": np.max([s["max"] for s in stats], axis=0).tolist(),
              "mean": mean.tolist(), "std": np.sqrt(variance).tolist(),
              "count": [int(counts.sum())]}
    for q, key in zip(QUANTILES, QUANTILE_KEYS, strict=True):
        if all(key in s for s in stats):
            bound = np.min if q <= 0.5 else np.max
            result[key] = bound([s[key] for s in stats], axis=0).tolist()
    return result


def as_image_stats(stats: dict) -> dict[str, list]:
    """Per-channel image statistics in LeRobot's (3, 1, 1) layout, count as [frames]; every
    statistic the recording has (quantiles too, once recorded) is carried."""
    return {key: [value] if key == "count" else [[[v]] for v in value]
            for key, value in stats.items()}
