"""Paired comparisons of two runs' episodes, as numbers: episodes paired by id (checked by their
episode hash and, where both records carry it, their realised start), each task's mean
difference, and per row (cell, level, average) the difference in IS / ES / CR with a
task-clustered 95% interval and a sign-flip p-value over tasks (intervals.py), adjusted by
Holm's method over the rows, per metric (docs/statistics.md)."""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import named
from robofollow.eval.statistics.intervals import holm, paired_test
from robofollow.eval.statistics.metrics import METRICS

ALPHA = 0.05  # the level a difference is told apart at (after Holm)
FIELDS = {"IS": "intent", "ES": "execution", "CR": "complete"}  # each metric in run_scores


@dataclass
class Pairing:
    """The episodes two runs share, and those left out."""
    pairs: list[tuple[dict, dict]] = field(default_factory=list)
    only_a: list[str] = field(default_factory=list)
    only_b: list[str] = field(default_factory=list)
    other_episode: list[str] = field(default_factory=list)  # same id, other episode hash
    other_start: list[str] = field(default_factory=list)  # same episode, starts apart

    def warnings(self, a: str, b: str) -> list[str]:
        found = []
        for episodes, what in ((self.only_a, f"only in {a}"), (self.only_b, f"only in {b}"),
                               (self.other_episode, ("that are other episodes (their "
                                                     "episode hashes differ: other specs?)")),
                               (self.other_start, ("that started further apart than the "
                                                   "start tolerance (their start hashes "
                                                   "differ)"))):
            if episodes:
                found.append(f"{len(episodes)} episode(s) {what}, left out: {named(episodes)}")
        return found


def pair(a: list[dict], b: list[dict]) -> Pairing:
    """Pair episodes by id; those whose episode hashes differ, or whose start hashes differ
    where both records have one, are left out."""
    by_id = {row["episode"]: row for row in b}
    pairing = Pairing()
    for row in sorted(a, key=lambda r: r["episode"]):
        other = by_id.pop(row["episode"], None)
        if other is None:
            pairing.only_a.append(row["episode"])
        elif row["hash"] and other["hash"] and row["hash"] != other["hash"]:
            pairing.other_episode.append(row["episode"])
        elif row.get("start") and other.get("start") and row["start"] != other["start"]:
            pairing.other_start.append(row["episode"])
        else:
            pairing.pairs.append((row, other))
    pairing.only_b = sorted(by_id)
    return pairing


def _task_differences(pairs: list[tuple[dict, dict]]) -> dict[str, dict]:
    """Per task: its cell, paired episodes, and each metric's mean A, B and A - B (0-1)."""
    grouped: dict[str, list[tuple[dict, dict]]] = defaultdict(list)
    for a, b in pairs:
        grouped[a["task"]].append((a, b))
    tasks = {}
    for task, group in grouped.items():
        entry = {"cell": (group[0][0]["scene"], group[0][0]["level"]), "episodes": len(group)}
        for metric, name in FIELDS.items():
            a = np.mean([float(x[name]) for x, _ in group])
            b = np.mean([float(y[name]) for _, y in group])
            entry[metric] = (a, b)
        tasks[task] = entry
    return tasks


def _row(label: dict, tasks: list[dict], cells: dict[tuple, float]) -> dict:
    """One row: per metric, A and B, the difference with its interval and p-value (points).
    `cells` weighs each task's cell (1 for one cell; 1 / its total for cells averaged)."""
    row = dict(label, tasks=len(tasks), episodes=sum(t["episodes"] for t in tasks))
    for metric in METRICS:
        base = np.array([t["episodes"] if metric != "CR" else 1.0 for t in tasks])
        totals = defaultdict(float)
        for task, weight in zip(tasks, base, strict=True):
            totals[task["cell"]] += weight
        weights = np.array([w * cells[t["cell"]] / totals[t["cell"]]
                            for t, w in zip(tasks, base, strict=True)])
        a = np.array([t[metric][0] for t in tasks])
        b = np.array([t[metric][1] for t in tasks])
        test = paired_test(a - b, weights)
        difference, interval = test.in_points()
        row[metric] = {"A": 100 * float(np.average(a, weights=weights)),
                       "B": 100 * float(np.average(b, weights=weights)),
                       "difference": difference, "interval": interval, "p": test.p}
    return row


def with_holm(rows: list[dict]) -> list[dict]:
    """The rows, each metric's p-value adjusted by Holm's method over the rows ("p_holm")."""
    for metric in METRICS:
        for row, adjusted in zip(rows, holm([r[metric]["p"] for r in rows]), strict=True):
            row[metric]["p_holm"] = adjusted
    return rows


def paired_rows(pairing: Pairing) -> list[dict]:
    """The rows of a comparison: each scene x level cell, each level over several scenes (each
    scene's cell counting equally) and the average over every cell, with Holm's adjustment."""
    tasks = _task_differences(pairing.pairs)
    cells = sorted({t["cell"] for t in tasks.values()},
                   key=lambda c: (c[0], LEVELS.index(c[1]) if c[1] in LEVELS else 99))
    rows = [_row({"scene": s, "level": lv}, [t for t in tasks.values() if t["cell"] == (s, lv)],
                 {(s, lv): 1.0}) for s, lv in cells]
    for level in LEVELS:  # a level over several scenes (over one, it is that scene's cell)
        chosen = [t for t in tasks.values() if t["cell"][1] == level]
        spanned = {t["cell"] for t in chosen}
        if len(spanned) > 1:
            rows.append(_row({"scene": "all", "level": level}, chosen,
                             {c: 1.0 / len(spanned) for c in spanned}))
    if len(cells) > 1:
        rows.append(_row({"scene": "all", "level": "avg"}, list(tasks.values()),
                         {c: 1.0 / len(cells) for c in cells}))
    return with_holm(rows)
