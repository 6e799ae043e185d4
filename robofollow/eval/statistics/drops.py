"""The mirage with intervals: each scene's drop from L0 to L1, L2 and L3 in one run.

An L1 task is an L0 task (the same training instruction) on a changed layout, so the L0 -> L1
drop is paired by training task: each task's L0 score minus the mean of its L1 tasks, weighted
by its L1 tasks (so the L1 side is the L1 cell's score), with an interval over training tasks
and a sign-flip p-value. L2 and L3 hold other tasks (new
wordings), so their drops are unpaired: the difference of the levels' task means, with a
bootstrap that resamples each level's tasks apart and a permutation p-value. p-values are
Holm-adjusted over the rows of a metric (docs/statistics.md).
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from robofollow.eval.statistics.intervals import paired_test, unpaired_test
from robofollow.eval.statistics.metrics import METRICS, RECORD_FIELDS
from robofollow.eval.statistics.paired import with_holm


def origin(task_id: str) -> str:
    """The training task an L0 or L1 task id names: scene2/L1/pickup_cube@scene2_1 ->
    pickup_cube."""
    return task_id.split("/", 2)[2].partition("@")[0]


def level_drops(results: list[dict]) -> list[dict]:
    """Per scene and later level: the L0 score, the level's, and the drop (L0 - level, points)
    with its interval and p-values, per metric; "paired" says how it was compared. The same
    in any record order."""
    means: dict[tuple[str, str], dict[str, dict[str, float]]] = defaultdict(dict)
    grouped: dict[tuple[str, str, str], list[dict]] = defaultdict(list)
    for record in results:
        grouped[record["scene"], record["level"], record["task"]].append(record)
    for (scene, level, task), records in sorted(grouped.items()):
        means[scene, level][task] = {m: float(np.mean([float(r[f]) for r in records]))
                                     for m, f in RECORD_FIELDS.items()}
    rows = []
    for scene in sorted({scene for scene, _ in means}):
        base = means.get((scene, "L0"))
        for level in ("L1", "L2", "L3"):
            later = means.get((scene, level))
            if not base or not later:
                continue
            if level == "L1" and not {origin(t) for t in base} & {origin(t) for t in later}:
                continue  # a sample whose L1 tasks come from none of its L0 tasks
            row = {"scene": scene, "level": level, "paired": level == "L1"}
            for metric in METRICS:
                row[metric], row["tasks"] = _drop(base, later, metric, paired=level == "L1")
            rows.append(row)
    return with_holm(rows)


def _drop(base: dict[str, dict], later: dict[str, dict], metric: str,
          paired: bool) -> tuple[dict, tuple[int, int]]:
    """One metric's drop, and the tasks it reads on each side (paired: the training tasks
    both levels have, and their L1 tasks)."""
    if paired:
        by_origin: dict[str, list[float]] = defaultdict(list)
        for task, values in later.items():
            by_origin[origin(task)].append(values[metric])
        l0 = {origin(task): values[metric] for task, values in base.items()}
        labels = sorted(set(l0) & set(by_origin))
        first = np.array([l0[label] for label in labels])
        second = np.array([np.mean(by_origin[label]) for label in labels])
        weights = np.array([len(by_origin[label]) for label in labels], float)  # its L1 tasks
        test = paired_test(first - second, weights)
        counts = len(labels), int(weights.sum())
    else:
        first = np.array([values[metric] for values in base.values()])
        second = np.array([values[metric] for values in later.values()])
        weights = None
        test = unpaired_test(first, second)
        counts = len(first), len(second)
    drop, interval = test.in_points()
    return {"L0": 100 * float(np.average(first, weights=weights)),
            "level": 100 * float(np.average(second, weights=weights)),
            "drop": drop, "interval": interval, "p": test.p}, counts
