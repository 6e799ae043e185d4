"""A finished run read back: its options (RUN/run.json) and its episodes, from the full
records (RUN/episodes.jsonl) or, where a run keeps only those (the runs docs/results ships),
the compact records of its score file (RUN/scores.csv.gz)."""

from __future__ import annotations

import json
from pathlib import Path

from robofollow.errors import RoboFollowError
from robofollow.eval.run_folder import RESULTS, RUN_FILE, SCORES, SUMMARY, read_results
from robofollow.eval.runner import EvalOptions
from robofollow.eval.scores import compact_records, holds_reported, read_scores


class RunReadError(RoboFollowError):
    """A folder that holds no evaluation run, or not the part of one that is asked for."""


def load_options(run: Path) -> EvalOptions:
    if not (run / RUN_FILE).is_file():
        what = "no such folder" if not run.is_dir() else f"no {RUN_FILE}"
        raise RunReadError(f"{run} holds no evaluation run ({what})")
    data = json.loads((run / RUN_FILE).read_text(encoding="utf-8"))
    return EvalOptions(**dict(data, scenes=tuple(data["scenes"]),
                              levels=tuple(data["levels"]), tasks=tuple(data["tasks"])))


def load_records(run: Path, reported: bool = False) -> list[dict]:
    """The run's episode records: full where it keeps them, else compact. `reported`: the
    records must hold what a report reads (a score file written before it kept that does
    not)."""
    if (run / RESULTS).is_file():
        return read_results(run / RESULTS)
    if (run / SCORES).is_file():
        if reported and not holds_reported(run / SCORES):
            raise RunReadError(f"{run} keeps only {SCORES}, written before it kept what the "
                               "report shows; its report cannot be rebuilt")
        return compact_records(read_scores(run / SCORES))
    if not run.is_dir():
        raise RunReadError(f"{run}: no such run folder")
    if (run / RUN_FILE).is_file():
        raise RunReadError(f"{run} holds an evaluation run but none of its episodes (no "
                           f"{RESULTS} or {SCORES})")
    raise RunReadError(f"{run} holds no evaluation run (no {RUN_FILE}, {RESULTS} or {SCORES})")


def load_run(run: Path) -> tuple[EvalOptions, list[dict]]:
    """The run's options and the records a report reads."""
    return load_options(run), load_records(run, reported=True)


def summarised_episodes(run: Path) -> int | None:
    """How many episodes the run's summary (RUN/summary.json) counts, if it has one."""
    path = run / SUMMARY
    if not path.is_file():
        return None
    try:
        return int(json.loads(path.read_text(encoding="utf-8"))["episodes"])
    except (ValueError, KeyError, TypeError):
        return None
