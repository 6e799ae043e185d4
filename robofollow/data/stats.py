"""Feature statistics as LeRobot stores them: min, max, mean, std (population) and count, per
episode and aggregated over episodes."""

from __future__ import annotations

import numpy as np

STAT_KEYS = ("min", "max", "mean", "std", "count")


def array_stats(values: np.ndarray) -> dict[str, list]:
    """Statistics over the first axis of a (N,) or (N, D) array."""
    values = np.asarray(values, dtype=np.float64)
    values = values.reshape(len(values), -1)
    return {"min": values.min(0).tolist(), "max": values.max(0).tolist(),
            "mean": values.mean(0).tolist(), "std": values.std(0).tolist(),
            "count": [len(values)]}


def aggregate(stats: list[dict[str, list]]) -> dict[str, list]:
    """One feature's statistics over several episodes: count-weighted mean, pooled variance."""
    counts = np.array([s["count"][0] for s in stats], dtype=np.float64)
    means = np.array([s["mean"] for s in stats], dtype=np.float64)
    variances = np.square(np.array([s["std"] for s in stats], dtype=np.float64))
    weights = (counts / counts.sum()).reshape((-1,) + (1,) * (means.ndim - 1))
    mean = (weights * means).sum(0)
    variance = (weights * (variances + np.square(means - mean))).sum(0)
    return {"min": np.min([s["min"] for s in stats], axis=0).tolist(),
            "max": np.max([s["max"] for s in stats], axis=0).tolist(),
            "mean": mean.tolist(), "std": np.sqrt(variance).tolist(),
            "count": [int(counts.sum())]}


def as_image_stats(stats: dict) -> dict[str, list]:
    """Per-channel image statistics in LeRobot's (3, 1, 1) layout."""
    return {key: ([[[v]] for v in stats[key]] if key != "count" else [stats["count"]])
            for key in STAT_KEYS}
