"""The paper's metrics over scored episodes.

Per scene x level: IS and ES are means over episodes; CR is the mean over tasks of each task's
completion rate (a task macro average; the episode micro average is kept too). Avg is the
mean over the scene x level cells. Everything is reported on a 0-100 scale.

Each cell also carries two 95% intervals for each metric:
- "ci95_tasks": a cluster bootstrap over the cell's tasks (intervals.py), the one to read: the
  rounds of one task are correlated, and the tasks are the independent units (None for a cell
  of one task; where every task has the same value there is nothing to resample, and it is the
  Wilson interval over the tasks);
- "ci95": the Wilson score interval over its episodes, as if every episode were independent
  (too narrow when the rounds of a task agree; kept beside it to show by how much).

L1 and L3 cells also split their episodes by the task's motion ("by_motion"): "moved" (the
expert moves otherwise than in the training task) and "as-trained" (it moves as trained; a
policy that replays the trained motion for the trained sentence passes these), each with IS,
ES, CR and its episode and task counts (None where the cell has none), and "unknown": the
episodes whose records do not say (written before records carried it, or a listed test).

Episodes that carry references (an evaluation's `chance` and `followed_intent`) add their means
to each cell: chance_IS / chance_CR (a language-blind guess) and followed_IS (perfectly
following the instruction given), and their averages under "references".
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping

import numpy as np

from robofollow.compiler.scene.spec import MOTION_LEVELS
from robofollow.eval.statistics.intervals import task_interval

METRICS = ("IS", "ES", "CR")
RECORD_FIELDS = {"IS": "intent_score", "ES": "execution_score", "CR": "complete"}  # per episode
MOTIONS = ("moved", "as-trained")  # an L1 / L3 task's motion, against its training task's
REFERENCES = ("chance_IS", "chance_CR", "followed_IS")  # when the episodes carry them


def table(results: Iterable[Mapping]) -> dict:
    """`results`: one mapping per episode with scene, level, task, intent_score,
    execution_score and complete. Returns {"cells": {scene: {level: {...}}}, "avg": {...}} and,
    when every cell has them, "references": {...}."""
    grouped: dict[tuple[str, str], list[Mapping]] = defaultdict(list)
    for result in results:
        grouped[result["scene"], result["level"]].append(result)
    cells: dict[str, dict[str, dict]] = {}
    for (scene, level), episodes in sorted(grouped.items()):
        cells.setdefault(scene, {})[level] = {**scores(episodes), **references(episodes)}
        cell = cells[scene][level]
        cell["ci95"] = {m: wilson(cell[m] / 100, len(episodes)) for m in METRICS}
        cell["ci95_tasks"] = task_intervals(episodes)
        if level in MOTION_LEVELS:
            cell["by_motion"] = by_motion(episodes)
    flat = [cell for levels in cells.values() for cell in levels.values()]
    averages = {"avg": {m: _mean(flat, m) for m in METRICS}}
    shown = [m for m in REFERENCES if flat and all(m in c for c in flat)]
    if shown:
        averages["references"] = {m: _mean(flat, m) for m in shown}
    return {"cells": cells, **averages}


def scores(episodes: list[Mapping]) -> dict:
    """IS, ES, CR (task macro average), CR_micro and the episode and task counts."""
    tasks: dict[str, list[bool]] = defaultdict(list)
    for e in episodes:
        tasks[e["task"]].append(bool(e["complete"]))
    return {"IS": _percent(e["intent_score"] for e in episodes),
            "ES": _percent(e["execution_score"] for e in episodes),
            "CR": _percent(np.mean(done) for done in tasks.values()),
            "CR_micro": _percent(e["complete"] for e in episodes),
            "episodes": len(episodes), "tasks": len(tasks)}


def task_intervals(episodes: list[Mapping]) -> dict[str, list[float] | None]:
    """Each metric's 95% cluster-bootstrap interval over the episodes' tasks (0-100 scale)."""
    tasks: dict[str, list[Mapping]] = defaultdict(list)
    for e in episodes:
        tasks[e["task"]].append(e)
    found = {}
    for metric, field in RECORD_FIELDS.items():
        means = [np.mean([float(e[field]) for e in group]) for group in tasks.values()]
        # IS and ES are episode means (a task weighs its episodes), CR a task average
        weights = [1 if metric == "CR" else len(group) for group in tasks.values()]
        interval = task_interval(means, weights)
        if interval is None:
            found[metric] = None
        elif interval[0] == interval[1]:  # every task alike: nothing to resample
            found[metric] = wilson(interval[0], len(tasks))
        else:
            found[metric] = [round(100 * interval[0], 1), round(100 * interval[1], 1)]
    return found


def shown_interval(cell: Mapping, metric: str) -> list[float]:
    """A cell's interval as reports read it: over its tasks, else (a cell of one task) the
    Wilson interval over its episodes."""
    return cell["ci95_tasks"][metric] or cell["ci95"][metric]


def by_motion(episodes: list[Mapping]) -> dict:
    """A cell's episodes split by their task's motion: {"moved": scores or None,
    "as-trained": scores or None, "unknown": the episodes whose record does not say}."""
    split = {kind: [e for e in episodes if e.get("motion") == kind] for kind in MOTIONS}
    return {**{kind: scores(subset) if subset else None for kind, subset in split.items()},
            "unknown": len(episodes) - sum(len(subset) for subset in split.values())}


def wilson(proportion: float, n: int, z: float = 1.959964) -> list[float]:
    """The Wilson score interval of a proportion observed over n trials, on a 0-100 scale."""
    if n <= 0:
        return [0.0, 100.0]
    p = min(1.0, max(0.0, proportion))
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return [round(float(100 * max(0.0, centre - half)), 1),
            round(float(100 * min(1.0, centre + half)), 1)]


def _mean(cells: list[dict], key: str) -> float:
    return round(float(np.mean([c[key] for c in cells])), 2) if cells else 0.0


def references(episodes: list[Mapping]) -> dict:
    """The episodes' chance_IS, chance_CR and followed_IS (0-100), where every one carries them."""
    found = {}
    if all("chance" in e for e in episodes):
        found["chance_IS"] = _percent(e["chance"]["IS"] for e in episodes)
        found["chance_CR"] = _percent(e["chance"]["CR"] for e in episodes)
    if all(e.get("followed_intent") is not None for e in episodes):
        found["followed_IS"] = _percent(e["followed_intent"] for e in episodes)
    return found


def _percent(values: Iterable) -> float:
    return round(100.0 * float(np.mean([float(v) for v in values])), 2)
