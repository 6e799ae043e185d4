"""`robofollow compare`: is run A really better than run B? Episodes are paired by their id
and checked by their episode hash (the compiled episode: task, layout, seed) and, where both
records carry it, the hash of their realised start (runner.start_hash, within its tolerance);
each difference in IS / ES / CR comes with a
task-clustered 95% interval and a sign-flip p-value over tasks (oracle/intervals.py), adjusted
by Holm's method over every row compared, per metric (docs/statistics.md).

Rows: each scene x level cell, each level over the scenes (each scene's cell counting
equally, as Table 1's averages do) and the average over every cell.
"""

from __future__ import annotations

import json
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robofollow.compiler.spec import LEVELS
from robofollow.errors import RoboFollowError, UsageError
from robofollow.eval.pages import PAGES, p_value, signed_interval
from robofollow.eval.run_folder import (
    RUN_FILE,
    check_folder_out,
    safe_path,
    write_text_file,
)
from robofollow.eval.saved_run import RunReadError, load_provenance, load_records
from robofollow.oracle.intervals import holm, paired_test
from robofollow.oracle.metrics import METRICS
from robofollow.provenance import differences

ALPHA = 0.05
FIELDS = {"IS": "intent", "ES": "execution", "CR": "complete"}  # each metric in run_scores
NAMED = 5  # episodes named in a warning or an error


class CompareError(RoboFollowError):
    """Runs that cannot be compared."""


def run_scores(run: Path) -> list[dict]:
    """A run's episodes as {episode, scene, level, task, hash, start, intent, execution,
    complete}: from its full records (RUN/episodes.jsonl) or, where a run keeps only those,
    its score file (RUN/scores.csv.gz)."""
    try:
        records = load_records(run)
    except RunReadError as error:
        raise CompareError(str(error)) from None
    return [{"episode": r["episode"], "scene": r["scene"], "level": r["level"],
             "task": r["task"], "hash": r.get("hashes", {}).get("episode", ""),
             "start": r.get("hashes", {}).get("start", ""),
             "intent": float(r["intent_score"]), "execution": float(r["execution_score"]),
             "complete": bool(r["complete"])} for r in records]


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


def compare_runs(a: Path, b: Path, names: tuple[str, str] | None = None) -> dict:
    """The paired comparison of run B with run A: {"a", "b", "pairing", "warnings", "rows",
    "verdicts"}; differences are A - B in points. `names`: what the verdicts call the runs
    (default: their folders' names)."""
    first, second = names or (a.name, b.name)
    pairing = pair(run_scores(a), run_scores(b))
    if not pairing.pairs:
        raise CompareError(f"{a} and {b} share no episode: nothing to compare (were they run "
                           "on the same specs?)")
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
    with_holm(rows)
    return {"a": str(a), "b": str(b),
            "pairing": {"pairs": len(pairing.pairs), "only_a": len(pairing.only_a),
                        "only_b": len(pairing.only_b),
                        "other_episode": len(pairing.other_episode),
                        "other_start": len(pairing.other_start)},
            "warnings": pairing.warnings(first, second), "rows": rows,
            "verdicts": [verdict(row, first, second) for row in _headline(rows)]}


def with_holm(rows: list[dict]) -> list[dict]:
    """The rows, each metric's p-value adjusted by Holm's method over the rows ("p_holm")."""
    for metric in METRICS:
        for row, adjusted in zip(rows, holm([r[metric]["p"] for r in rows]), strict=True):
            row[metric]["p_holm"] = adjusted
    return rows


def named(items: list[str]) -> str:
    """The first NAMED items, and how many more."""
    more = f" and {len(items) - NAMED} more" if len(items) > NAMED else ""
    return ", ".join(items[:NAMED]) + more


def _headline(rows: list[dict]) -> list[dict]:
    """The rows a verdict is given for: each level (its cell where one scene has it), then
    the average."""
    chosen = []
    for level in (*LEVELS, "avg"):
        found = [r for r in rows if r["level"] == level]
        pooled = [r for r in found if r["scene"] == "all"]
        chosen += pooled or found
    return chosen


CONTROLS = "controls"  # RUN/controls/<instruction mode>: a run's control arms


def control_arms(run: Path) -> list[str]:
    """The modes of the run's control arms (RUN/controls/<mode> holding a run), sorted."""
    folder = run / CONTROLS
    return sorted(arm.name for arm in folder.iterdir()
                  if (arm / RUN_FILE).is_file()) if folder.is_dir() else []


def environment_warnings(runs: list[Path]) -> list[str]:
    """For each later run whose recorded environment is not the first run's, the fields in
    which they differ (provenance.FIELDS): trajectory hashes are comparable only where the
    arithmetic fields agree; scores are comparable everywhere."""
    made = [load_provenance(run) for run in runs]
    warnings = []
    for run, entries in zip(runs[1:], made[1:], strict=True):
        if entries == made[0]:
            continue
        if not entries or not made[0]:
            lacking = runs[0] if not made[0] else run
            warnings.append(f"{lacking} records no environment (made before runs recorded "
                            f"one): {runs[0].name} and {run.name} may differ in any version")
            continue
        found = differences(made[0][0], entries[0]) or ["the environments of resumed parts"]
        warnings.append(f"{runs[0].name} and {run.name} ran in different environments: "
                        f"{'; '.join(found)}")
    return warnings


def control_comparisons(run: Path) -> list[dict]:
    """The run against each of its control arms (RUN/controls/<mode>, same episodes with
    other instructions): {"mode", "folder", "pairs", "verdicts", "rows"}; none when it has
    none."""
    found = []
    for mode in control_arms(run):
        result = compare_runs(run, run / CONTROLS / mode, ("instructed", mode))
        found.append({"mode": mode, "folder": f"{CONTROLS}/{mode}",
                      "pairs": result["pairing"]["pairs"], "verdicts": result["verdicts"],
                      "rows": result["rows"], "warnings": result["warnings"]})
    return found


def verdict(row: dict, a: str, b: str, metric: str = "IS") -> str:
    """One line: which run is ahead on `metric` in a row, by how much, and whether the
    difference holds at the 5% level after Holm's adjustment."""
    cell = row[metric]
    where = ("on average" if row["level"] == "avg" else f"at {row['level']}"
             + ("" if row["scene"] == "all" else f" in {row['scene']}"))
    shown = _signed(cell["difference"]) + (" " + signed_interval(cell["interval"]))
    p = p_value(cell["p_holm"])
    tail = f"p {p if p.startswith('<') else '= ' + p} (Holm), {row['tasks']} tasks, " \
           f"{row['episodes']} pairs"
    if cell["p_holm"] < ALPHA:
        ahead, behind = (a, b) if cell["difference"] > 0 else (b, a)
        return f"{ahead} > {behind} {where} ({metric}): {shown}, {tail}"
    return f"{a} ≈ {b} {where} ({metric}): {shown}, {tail}: not told apart"


def _signed(value: float) -> str:
    return f"{value:+.1f}"


_PLOT = {"width": 520, "row": 22, "label": 170, "top": 28}  # a forest plot's geometry (px)


def forest(result: dict, metric: str) -> dict:
    """A forest plot of a metric's differences: each row's estimate and interval in pixels,
    the zero line, and ticks (the SVG in compare.html.j2 draws it)."""
    rows = result["rows"]
    values = [0.0] + [v for r in rows for v in [r[metric]["difference"],
                                                *(r[metric]["interval"] or [])]]
    low, high = min(values), max(values)
    pad = max((high - low) * 0.05, 1.0)
    low, high = low - pad, high + pad
    step = next(s for s in (1, 2, 5, 10, 20, 25, 50) if (high - low) / s <= 10)

    def x(value: float) -> float:
        return round(_PLOT["label"] + (value - low) / (high - low) * _PLOT["width"], 1)

    drawn = []
    for index, row in enumerate(rows):
        cell = row[metric]
        bounds = cell["interval"] or [cell["difference"], cell["difference"]]
        name = f"{row['scene']} {row['level']}".replace("all avg", "average")
        drawn.append({"label": f"{name} · {row['tasks']} tasks",
                      "y": _PLOT["top"] + index * _PLOT["row"], "x": x(cell["difference"]),
                      "low": x(bounds[0]), "high": x(bounds[1]),
                      "told_apart": cell["p_holm"] < ALPHA,
                      "title": f"{cell['difference']:+.1f} {signed_interval(cell['interval'])}, "
                               f"p (Holm) {p_value(cell['p_holm'])}, {row['tasks']} tasks, "
                               f"{row['episodes']} pairs"})
    first = step * np.ceil(low / step)
    ticks = [{"x": x(v), "label": f"{v:+g}" if v else "0"} for v in np.arange(first, high, step)]
    return {"rows": drawn, "zero": x(0.0), "ticks": ticks, "metric": metric,
            "height": _PLOT["top"] + len(rows) * _PLOT["row"] + 24,
            "width": _PLOT["label"] + _PLOT["width"] + 20}


def html(result: dict) -> str:
    """The comparison as a page: verdicts, a forest plot and a table per metric."""
    return PAGES.get_template("compare.html.j2").render(
        result=result, a=Path(result["a"]).name, b=Path(result["b"]).name, metrics=METRICS,
        plots={metric: forest(result, metric) for metric in METRICS})


def markdown(result: dict) -> str:
    """The comparison as markdown: verdicts, then a table per metric."""
    a, b = Path(result["a"]).name, Path(result["b"]).name
    pairing = result["pairing"]
    lines = [f"# {a} − {b}", "",
             (f"{pairing['pairs']} paired episodes (by id, the same episode hash and, where "
              "recorded, the same start); "
              f"differences are {a} − {b} in points, with 95% intervals over tasks (a cluster "
              "bootstrap) and sign-flip p-values over tasks, adjusted by Holm's method over "
              "every row of a metric (docs/statistics.md)."), ""]
    lines += [f"- {warning}" for warning in result["warnings"]]
    lines += ["", "## Verdicts (Intent)", ""] + [f"- {v}" for v in result["verdicts"]]
    for metric in METRICS:
        lines += ["", f"## {metric}", "",
                  f"| Scene | Level | {a} | {b} | Δ | 95% interval | p | p (Holm) | n |",
                  "|---|---|---:|---:|---:|---|---:|---:|---|"]
        for row in result["rows"]:
            cell = row[metric]
            n = f"{row['tasks']} tasks, {row['episodes']} pairs"
            lines.append(f"| {row['scene']} | {row['level']} | {cell['A']:.1f} | "
                         f"{cell['B']:.1f} | {_signed(cell['difference'])} | "
                         f"{signed_interval(cell['interval'])} | {p_value(cell['p'])} | "
                         f"{p_value(cell['p_holm'])} | {n} |")
    return "\n".join(lines) + "\n"


def comparison_folders(a: Path, others: list[Path], out: Path) -> list[Path]:
    """Where each comparison of `others` with `a` is written: `out` for one; else
    out/<A>-vs-<B>, each B named by as many of its last path parts as tell the runs apart
    (two comparisons never share a folder)."""
    if len(others) == 1:
        return [out]
    if len({other.resolve() for other in others}) < len(others):
        raise UsageError("a run is given twice; each run is compared with the first once")
    names = [other.name for other in others]
    for depth in range(1, max(len(other.resolve().parts) for other in others) + 1):
        names = ["-".join(other.resolve().parts[-depth:]) for other in others]
        if len(set(names)) == len(names):
            break
    return [out / f"{a.name}-vs-{name}" for name in names]


def write_comparison_files(result: dict, out: Path) -> None:
    """OUT/compare.md, compare.html and compare.json of one comparison."""
    check_folder_out(out)
    for name, text in (("compare.md", markdown(result)), ("compare.html", html(result)),
                       ("compare.json", json.dumps(result, indent=2) + "\n")):
        write_text_file(safe_path(out, name), text)
