"""Intervals and tests that treat a benchmark's tasks, not its episodes, as the independent
units (docs/statistics.md).

The rounds of one task share its instruction, layout and expert motion, so their outcomes are
correlated: a cell of 16 tasks x 10 rounds holds about 16 independent units, not 160. Every
statistic here is a weighted mean of per-task values, sum(w * v) / sum(w), where a task's
value is its mean over the episodes it has (a score, or a paired difference) and its weight
says how much it counts (its episodes for IS and ES, one for CR's task average). Intervals are
BCa cluster bootstraps over tasks; paired differences are tested by flipping the sign of each
task's difference (exact when there are few tasks). Every resampling is seeded: the same
values give the same intervals and p-values.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import stats

SEED = 20261126  # every resampling starts here
RESAMPLES = 4000  # bootstrap resamples
PERMUTATIONS = 20000  # sign flips drawn when there are too many to list (2 ** tasks)
CONFIDENCE = 0.95


def weighted_mean(values: np.ndarray, weights: np.ndarray, axis: int = -1) -> np.ndarray:
    return (values * weights).sum(axis) / weights.sum(axis)


def task_interval(values, weights) -> tuple[float, float] | None:
    """The 95% cluster-bootstrap (BCa) interval of sum(w * v) / sum(w) over tasks; None with
    fewer than two tasks (one task says nothing of how tasks vary). Tasks that all have one
    value give that value as both ends."""
    values, weights = np.asarray(values, float), np.asarray(weights, float)
    if len(values) < 2:
        return None
    if np.ptp(values) == 0:
        return float(values[0]), float(values[0])
    return _bootstrap((values, weights), weighted_mean, paired=True)


def _bootstrap(data: tuple, statistic, paired: bool) -> tuple[float, float]:
    """The BCa interval, or the percentile one where BCa is undefined (a resampling
    distribution too flat for its acceleration: scipy warns and gives NaN)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
        result = stats.bootstrap(data, statistic, paired=paired, vectorized=True,
                                 n_resamples=RESAMPLES, confidence_level=CONFIDENCE,
                                 method="BCa", rng=np.random.default_rng(SEED))
    low, high = result.confidence_interval
    if not (np.isfinite(low) and np.isfinite(high)):
        low, high = np.percentile(result.bootstrap_distribution, [2.5, 97.5])
    return float(low), float(high)


@dataclass(frozen=True)
class Difference:
    """A difference over tasks: its estimate, 95% interval (None: too few tasks to say) and
    two-sided p-value."""
    estimate: float
    interval: tuple[float, float] | None
    p: float
    tasks: int

    def in_points(self) -> tuple[float, list[float] | None]:
        """The estimate and the interval on the 0-100 scale."""
        interval = None if self.interval is None else [100 * v for v in self.interval]
        return 100 * self.estimate, interval


def paired_test(differences, weights) -> Difference:
    """The weighted mean of per-task differences (A - B), its cluster-bootstrap interval and
    the sign-flip permutation p-value of 'no difference' (every task's difference as likely
    negated; 1 for a single task, which cannot be tested)."""
    differences, weights = np.asarray(differences, float), np.asarray(weights, float)
    estimate = float(weighted_mean(differences, weights))
    interval = task_interval(differences, weights)
    if len(differences) < 2 or not np.any(differences):  # one task cannot be tested
        return Difference(estimate, interval, 1.0, len(differences))

    def statistic(flipped, axis=-1):
        return weighted_mean(flipped, weights, axis)

    test = stats.permutation_test((differences,), statistic, permutation_type="samples",
                                  vectorized=True, n_resamples=PERMUTATIONS,
                                  rng=np.random.default_rng(SEED))
    return Difference(estimate, interval, float(min(test.pvalue, 1.0)), len(differences))


def unpaired_test(first, second) -> Difference:
    """mean(first) - mean(second) over two sets of tasks that do not pair (each task's value
    counts once): a BCa bootstrap resampling each set's tasks apart, and the permutation
    p-value of 'the two sets are alike' (task values shuffled between them)."""
    first, second = np.asarray(first, float), np.asarray(second, float)
    estimate = float(first.mean() - second.mean())

    def difference(x, y, axis=-1):
        return x.mean(axis) - y.mean(axis)

    if len(first) < 2 or len(second) < 2:
        return Difference(estimate, None, 1.0, len(first) + len(second))
    if np.ptp(np.concatenate([first, second])) == 0:
        return Difference(estimate, (estimate, estimate), 1.0, len(first) + len(second))
    interval = estimate, estimate  # both sets constant: nothing to resample
    if np.ptp(first) or np.ptp(second):
        interval = _bootstrap((first, second), difference, paired=False)
    test = stats.permutation_test((first, second), difference, vectorized=True,
                                  n_resamples=PERMUTATIONS, rng=np.random.default_rng(SEED))
    return Difference(estimate, interval, float(min(test.pvalue, 1.0)), len(first) + len(second))


def holm(p_values: list[float]) -> list[float]:
    """Holm's step-down adjustment of p-values for testing them together (each adjusted
    p-value is compared with the level itself)."""
    order = np.argsort(p_values, kind="stable")
    adjusted = [0.0] * len(p_values)
    running = 0.0
    for rank, index in enumerate(order):
        running = max(running, min(1.0, (len(p_values) - rank) * p_values[index]))
        adjusted[index] = running
    return adjusted
