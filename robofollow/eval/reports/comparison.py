"""`robofollow compare`: is run A really better than run B? Episodes are paired by their id
and checked by their episode hash (the compiled episode: task, layout, seed) and, where both
records carry it, the hash of their realised start (runner.start_hash, within its tolerance);
each difference in IS / ES / CR comes with a task-clustered 95% interval and a sign-flip
p-value over tasks, adjusted by Holm's method over every row compared, per metric
(statistics/paired.py; docs/statistics.md). Runs made on different test sets (two releases, or
a release and a working compile) pair only on the episodes whose hash over what decides them
is the same in both (benchmark.episode_hash), and the comparison says how many.

Rows: each scene x level cell, each level over the scenes (each scene's cell counting
equally, as Table 1's averages do) and the average over every cell.
"""

from __future__ import annotations

from pathlib import Path

from robofollow import release
from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError
from robofollow.eval.reports.pages import p_value, signed, signed_interval
from robofollow.eval.running.run_benchmark import described, run_benchmark, run_release
from robofollow.eval.running.run_folder import CONTROLS, RUN_FILE, control_arms
from robofollow.eval.running.runner import EvalOptions
from robofollow.eval.running.saved_run import (
    RunReadError,
    load_options,
    load_provenance,
    load_records,
)
from robofollow.eval.statistics.paired import ALPHA, pair, paired_rows
from robofollow.provenance import differences

NOT_IN_RELEASE = "not in its release"  # the pairing hash of an episode its release lacks


class CompareError(RoboFollowError):
    """Runs that cannot be compared."""


def run_scores(run: Path, hashes: dict[str, str] | None = None) -> list[dict]:
    """A run's episodes as {episode, scene, level, task, hash, start, intent, execution,
    complete}: from its full records (RUN/episodes.jsonl) or, where a run keeps only those,
    its score file (RUN/scores.csv.gz). `hashes`: each episode's hash to pair by instead of
    the recorded one (`test_set_hashes`)."""
    try:
        records = load_records(run)
    except RunReadError as error:
        raise CompareError(str(error)) from None
    if hashes is not None:
        records = [dict(r, hashes={**r.get("hashes", {}),
                                   "episode": hashes.get(r["episode"], NOT_IN_RELEASE)})
                   for r in records]
    return [{"episode": r["episode"], "scene": r["scene"], "level": r["level"],
             "task": r["task"], "hash": r.get("hashes", {}).get("episode", ""),
             "start": r.get("hashes", {}).get("start", ""),
             "intent": float(r["intent_score"]), "execution": float(r["execution_score"]),
             "complete": bool(r["complete"])} for r in records]


def _test_set(options: EvalOptions) -> tuple[str, str]:
    """What a run's episodes come from: ("release", name), or ("specs", spec digest) for a
    working compile or specs no release was frozen from."""
    name = run_release(options)
    return ("release", name) if name else ("specs", options.spec_digest)


def test_set_hashes(runs: list[Path]) -> list[dict[str, str]] | None:
    """What the runs' episodes pair by: None where the runs share a test set (their recorded
    episode hashes); else, for each run, every episode's hash over what decides it, from its
    own release or working compile (release.content_hashes), so that only the episodes that
    are the same in both pair."""
    if not all((run / RUN_FILE).is_file() for run in runs):  # (folders of scores alone)
        return None
    options = [load_options(run) for run in runs]
    if len({_test_set(o) for o in options}) == 1:
        return None
    hashes = []
    for run, made in zip(runs, options, strict=True):
        try:
            benchmark = run_benchmark(run, made)
        except RoboFollowError as error:
            raise CompareError(f"{run} was made on another test set than {runs[0]}, and its "
                               f"own is not here to pair them: {error.render()}") from None
        hashes.append(release.content_hashes(benchmark))
    return hashes


def compare_runs(a: Path, b: Path, names: tuple[str, str] | None = None) -> dict:
    """The paired comparison of run B with run A: {"a", "b", "pairing", "warnings", "rows",
    "verdicts"}, and "test_sets" where the runs were made on different ones (only the episodes
    that are the same in both pair); differences are A - B in points. `names`: what the
    verdicts call the runs (default: their folders' names)."""
    first, second = names or (a.name, b.name)
    hashes = test_set_hashes([a, b])
    pairing = pair(*(run_scores(run, hashes and hashes[i]) for i, run in enumerate((a, b))))
    if not pairing.pairs:
        raise CompareError(f"{a} and {b} share no episode: nothing to compare (were they run "
                           "on the same specs?)")
    rows = paired_rows(pairing)
    warnings = pairing.warnings(first, second)
    found = {"a": str(a), "b": str(b),
             "pairing": {"pairs": len(pairing.pairs), "only_a": len(pairing.only_a),
                         "only_b": len(pairing.only_b),
                         "other_episode": len(pairing.other_episode),
                         "other_start": len(pairing.other_start)},
             "warnings": warnings, "rows": rows,
             "verdicts": [verdict(row, first, second) for row in _headline(rows)]}
    if hashes is not None:
        sets = [described(load_options(run)) for run in (a, b)]
        warnings.insert(0, f"{first} and {second} were made on different test sets ({first}: "
                           f"{sets[0]}; {second}: {sets[1]}): paired on the "
                           f"{len(pairing.pairs)} episodes that are the same in both, "
                           f"{len(pairing.other_episode)} of the ids both hold left out")
        found["test_sets"] = sets
    return found


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


