"""`robofollow compare --power DELTA PILOT [PILOT_B]`: how many rounds per task a comparison
of two policies needs to tell apart a difference of DELTA points at each level (or, `--by
cell`, in each scene x level cell), planned from a pilot run's variance, or better from two
pilot runs' paired differences (docs/statistics.md); and the power the pilot's own tasks and
rounds reach, Phi(DELTA / SE - z(1 - alpha / 2)), with SE^2 = k * (between + within / R) / T.

A level's estimate is a mean over its tasks of each task's mean over its rounds, so its
variance has two parts: how much tasks differ (between tasks, which only more tasks reduce)
and how much rounds of one task differ (within tasks, which rounds reduce). From the pilot,
per level: the within-task variance is the pooled variance of episodes around their task's
mean; the between-task variance is the variance of the task means less the within part they
carry (method of moments, at least 0). From two pilot runs these are the variances of their
paired differences; from one, a paired difference is taken to vary like one policy's scores
twice over (k = 2: the policies independent given the task, conservative where they are
alike, as paired policies usually are). The normal approximation then gives the rounds R with

    k * (between / T + within / (T * R)) <= (DELTA / (z(1 - alpha / 2) + z(power)))^2,

alpha split over the levels planned (Bonferroni, a bound on Holm's adjustment). Where even
unlimited rounds cannot reach it, the level needs more tasks, and the plan says how many.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
from scipy import stats

from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.eval.statistics.paired import FIELDS, pair

MAX_ROUNDS = 1000  # a plan beyond this many rounds per task is reported as out of reach


class PowerError(RoboFollowError):
    """Pilots that a plan cannot be made from."""


def _key(row: dict, by: str) -> str:
    return row["level"] if by == "level" else f"{row['scene']} {row['level']}"


def _series(runs: list[list[dict]], metric: str, by: str) -> dict[str, dict[str, list[float]]]:
    """Per group (level or cell) and task, the pilot's values in points: one run's scores, or
    two runs' paired differences (A - B, episodes paired by id)."""
    episodes: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    if len(runs) == 1:
        rows = [(row, 100.0 * float(row[FIELDS[metric]])) for row in runs[0]]
    else:
        pairing = pair(runs[0], runs[1])
        rows = [(a, 100.0 * (float(a[FIELDS[metric]]) - float(b[FIELDS[metric]])))
                for a, b in pairing.pairs]
    for row, value in rows:
        episodes[_key(row, by)][row["task"]].append(value)
    return episodes


def _order(group: str) -> tuple:
    """Groups in Table 1's order: by scene, then level (a level alone: by level)."""
    *scene, level = group.split(" ")
    return (*scene, LEVELS.index(level) if level in LEVELS else len(LEVELS))


def plan(runs: list[list[dict]], delta: float, metric: str = "IS", power: float = 0.8,
         alpha: float = 0.05, by: str = "level") -> list[dict]:
    """Per level (or, `by="cell"`, per scene x level cell) of the pilot (one run's scores, or
    two runs' to plan from their paired differences; rows as comparison.run_scores gives
    them): its tasks, rounds, the two standard deviations (points), the rounds per task
    needed ("rounds": None where rounds alone cannot do it, with "tasks_needed": how many
    tasks unlimited rounds would need) and the power its own tasks and rounds reach
    ("reached")."""
    episodes = _series(runs, metric, by)
    if not episodes:
        raise PowerError("the pilots share no episode: there is nothing to plan from (were "
                         "they run on the same test set?)" if len(runs) > 1 else
                         "the pilot holds no episode: there is nothing to plan from")
    twice = 2.0 if len(runs) == 1 else 1.0  # one run: a difference varies like two
    groups = sorted(episodes, key=_order)
    single = [g for g in groups if all(len(t) < 2 for t in episodes[g].values())]
    if single:
        raise PowerError(f"the pilot has one round of every task of {', '.join(single)}: the "
                         "spread within a task cannot be estimated from it; plan from a "
                         "pilot of two rounds or more (eval --rounds 2)")
    level_z = stats.norm.ppf(1 - alpha / (2 * max(len(groups), 1)))
    z = level_z + stats.norm.ppf(power)
    target = (delta / z) ** 2  # the variance the difference may have
    found = []
    for group in groups:
        tasks = list(episodes[group].values())
        count = len(tasks)
        rounds = float(np.mean([len(t) for t in tasks]))
        within = (float(np.mean([np.var(t, ddof=1) for t in tasks if len(t) > 1]))
                  if any(len(t) > 1 for t in tasks) else 0.0)
        means = [np.mean(t) for t in tasks]
        between = max(float(np.var(means, ddof=1)) - within / rounds, 0.0) if count > 1 else 0.0
        variance = twice * (between + within / rounds) / count
        reached = (float(stats.norm.cdf(delta / math.sqrt(variance) - level_z)) if variance > 0
                   else 1.0)
        entry = {by: group, "tasks": count, "pilot_rounds": rounds,
                 "between_sd": math.sqrt(between), "within_sd": math.sqrt(within),
                 "rounds": None, "tasks_needed": None, "reached": reached}
        room = count * target - twice * between
        needed = math.ceil(twice * within / room) if room > 0 else None
        if needed is not None and needed <= MAX_ROUNDS:
            entry["rounds"] = max(needed, 1)
        else:
            entry["tasks_needed"] = math.ceil(twice * between / target) + 1 if between else None
        found.append(entry)
    return found


def plan_markdown(runs: list[str], delta: float, metric: str, entries: list[dict]) -> str:
    """The plan as a markdown table."""
    by = "cell" if entries and "cell" in entries[0] else "level"
    pilot = (f"{runs[0]} as the pilot; a paired difference taken to vary like one "
             "policy's scores twice over" if len(runs) == 1 else
             f"the paired differences {runs[0]} − {runs[1]} as the pilot")
    lines = [f"# Rounds per task to tell apart {delta:g} points of {metric}", "",
             f"80% power, 5% two-sided split over the {by}s; {pilot} (docs/statistics.md).",
             "", (f"| {by.capitalize()} | tasks | pilot rounds | SD between tasks | SD within a "
                  "task | power reached | rounds per task needed |"),
             "|---|---:|---:|---:|---:|---:|---|"]
    for e in entries:
        if e["rounds"] is not None:
            needed = str(e["rounds"])
        elif e["tasks_needed"] is not None:
            needed = (f"out of reach by rounds: tasks differ too much; about "
                      f"{e['tasks_needed']} tasks would be needed")
        else:
            needed = "out of reach"
        lines.append(f"| {e[by]} | {e['tasks']} | {e['pilot_rounds']:g} | "
                     f"{e['between_sd']:.1f} | {e['within_sd']:.1f} | "
                     f"{100 * e['reached']:.0f}% | {needed} |")
    return "\n".join(lines) + "\n"
