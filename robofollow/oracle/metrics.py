"""The paper's metrics over scored episodes.

Per scene x level: IS and ES are means over episodes; CR is the mean over tasks of each task's
completion rate (a task macro average; the episode micro average is kept too). Avg is the
mean over the scene x level cells. Everything is reported on a 0-100 scale.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping

import numpy as np

METRICS = ("IS", "ES", "CR")


def table(results: Iterable[Mapping]) -> dict:
    """`results`: one mapping per episode with scene, level, task, intent_score,
    execution_score and complete. Returns {"cells": {scene: {level: {...}}}, "avg": {...}}."""
    grouped: dict[tuple[str, str], list[Mapping]] = defaultdict(list)
    for result in results:
        grouped[result["scene"], result["level"]].append(result)
    cells: dict[str, dict[str, dict]] = {}
    for (scene, level), episodes in sorted(grouped.items()):
        tasks: dict[str, list[bool]] = defaultdict(list)
        for e in episodes:
            tasks[e["task"]].append(bool(e["complete"]))
        cells.setdefault(scene, {})[level] = {
            "IS": _percent(e["intent_score"] for e in episodes),
            "ES": _percent(e["execution_score"] for e in episodes),
            "CR": _percent(np.mean(done) for done in tasks.values()),
            "CR_micro": _percent(e["complete"] for e in episodes),
            "episodes": len(episodes), "tasks": len(tasks)}
    flat = [cell for levels in cells.values() for cell in levels.values()]
    avg = {m: round(float(np.mean([c[m] for c in flat])), 2) if flat else 0.0 for m in METRICS}
    return {"cells": cells, "avg": avg}


def _percent(values: Iterable) -> float:
    return round(100.0 * float(np.mean([float(v) for v in values])), 2)
