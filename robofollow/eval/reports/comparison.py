"""`robofollow compare`: is run A really better than run B? Episodes are paired by their id
and checked by their episode hash (the compiled episode: task, layout, seed) and, where both
records carry it, the hash of their realised start (runner.start_hash, within its tolerance);
each difference in IS / ES / CR comes with a task-clustered 95% interval and a sign-flip
p-value over tasks, adjusted by Holm's method over every row compared, per metric
(statistics/paired.py; docs/statistics.md).

Rows: each scene x level cell, each level over the scenes (each scene's cell counting
equally, as Table 1's averages do) and the average over every cell.
"""

from __future__ import annotations

from pathlib import Path

from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.eval.reports.pages import p_value, signed, signed_interval
from robofollow.eval.running.run_folder import CONTROLS, control_arms
from robofollow.eval.running.saved_run import (
    RunReadError,
    load_provenance,
    load_records,
)
from robofollow.eval.statistics.paired import ALPHA, pair, paired_rows
from robofollow.provenance import differences


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


def compare_runs(a: Path, b: Path, names: tuple[str, str] | None = None) -> dict:
    """The paired comparison of run B with run A: {"a", "b", "pairing", "warnings", "rows",
    "verdicts"}; differences are A - B in points. `names`: what the verdicts call the runs
    (default: their folders' names)."""
    first, second = names or (a.name, b.name)
    pairing = pair(run_scores(a), run_scores(b))
    if not pairing.pairs:
        raise CompareError(f"{a} and {b} share no episode: nothing to compare (were they run "
                           "on the same specs?)")
    rows = paired_rows(pairing)
    return {"a": str(a), "b": str(b),
            "pairing": {"pairs": len(pairing.pairs), "only_a": len(pairing.only_a),
                        "only_b": len(pairing.only_b),
                        "other_episode": len(pairing.other_episode),
                        "other_start": len(pairing.other_start)},
            "warnings": pairing.warnings(first, second), "rows": rows,
            "verdicts": [verdict(row, first, second) for row in _headline(rows)]}


def _headline(rows: list[dict]) -> list[dict]:
    """The rows a verdict is given for: each level (its cell where one scene has it), then
    the average."""
    chosen = []
    for level in (*LEVELS, "avg"):
        found = [r for r in rows if r["level"] == level]
        pooled = [r for r in found if r["scene"] == "all"]
        chosen += pooled or found
    return chosen


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
    shown = signed(cell["difference"]) + (" " + signed_interval(cell["interval"]))
    p = p_value(cell["p_holm"])
    tail = f"p {p if p.startswith('<') else '= ' + p} (Holm), {row['tasks']} tasks, " \
           f"{row['episodes']} pairs"
    if cell["p_holm"] < ALPHA:
        ahead, behind = (a, b) if cell["difference"] > 0 else (b, a)
        return f"{ahead} > {behind} {where} ({metric}): {shown}, {tail}"
    return f"{a} ≈ {b} {where} ({metric}): {shown}, {tail}: not told apart"


