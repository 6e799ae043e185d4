"""RUN/scores.csv.gz: every episode in a compact file a run keeps (and the reference runs in
docs/results commit), so that later runs compare against it episode by episode and its report
can be rebuilt without the full records.

A row holds the episode id, its hash (what pairs two runs' episodes), its scene's split digest,
the task's motion, Intent, Execution, completion, the hash of its realised start on a grid
(runner.start_hash); then what the report reads: the layout, seed, chance and followed
Intent, what the policy did and its first failed stage (outcomes.py), clipped actions, steps,
the policy error, the video, the instruction given (and the task's own, where another was
given), the observation parts the policy read and the hash of its whole trajectory
(runner.trajectory_hash: what a rerun reproduces). Files written before a column was
added lack it (COLUMNS after the first seven). Byte-identical for the same records."""

from __future__ import annotations

import csv
import gzip
import io
from pathlib import Path

from robofollow.errors import RoboFollowError
from robofollow.eval.outcomes import closest, first_failure
from robofollow.files import write_bytes_atomic

COLUMNS = ("episode", "hash", "split", "motion", "intent", "execution", "complete", "start",
           "layout", "seed", "chance_is", "chance_cr", "followed", "did", "failed", "reason",
           "clipped", "steps", "error", "video", "instruction", "task_instruction", "observed",
           "trajectory")
# what a report rebuilt from the file needs beyond the scores
REPORTED = COLUMNS[8:COLUMNS.index("task_instruction")]


def score_rows(results: list[dict]) -> list[dict]:
    """One row per record, in episode order."""
    return [_row(r) for r in sorted(results, key=lambda r: r["episode"])]


def _row(r: dict) -> dict:
    hashes, chance = r.get("hashes", {}), r.get("chance") or {}
    failed = first_failure(r) if "stages" in r or "first_failure" in r else None
    followed = r.get("followed_intent")
    return {"episode": r["episode"], "hash": hashes.get("episode", ""),
            "split": hashes.get("split", ""), "motion": r.get("motion") or "",
            "intent": f"{r['intent_score']:.4f}", "execution": f"{r['execution_score']:.4f}",
            "complete": int(bool(r["complete"])), "start": hashes.get("start", ""),
            "layout": r.get("layout", ""), "seed": r.get("seed", ""),
            "chance_is": _number(chance.get("IS")), "chance_cr": _number(chance.get("CR")),
            "followed": _number(followed),
            "did": closest(r) if "executed_behaviour" in r or "did" in r else "",
            "failed": failed[0] if failed else "", "reason": failed[1] if failed else "",
            "clipped": r.get("clipped", 0), "steps": r.get("steps", ""),
            "error": r.get("error") or "", "video": r.get("video") or "",
            "instruction": r.get("instruction") or "",
            "task_instruction": r.get("task_instruction") or "",
            "observed": ",".join(r.get("observed", ())),
            "trajectory": hashes.get("trajectory", "")}


def _number(value: float | None) -> str:
    return "" if value is None else f"{value:.6g}"


def write_scores(path: Path, results: list[dict]) -> None:
    text = io.StringIO()
    writer = csv.DictWriter(text, COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(score_rows(results))
    write_bytes_atomic(path, gzip.compress(text.getvalue().encode(), mtime=0))


def read_scores(path: Path) -> list[dict]:
    """The rows of a scores file: intent and execution as floats, complete as a bool."""
    try:
        rows = list(csv.DictReader(io.StringIO(gzip.decompress(path.read_bytes()).decode())))
    except (OSError, EOFError, UnicodeDecodeError, csv.Error) as error:
        raise RoboFollowError(f"{path}: not a scores file ({error})") from None
    lacking = sorted(set(COLUMNS[:7]) - set(rows[0])) if rows else []
    if lacking:
        raise RoboFollowError(f"{path}: lacks the columns {', '.join(lacking)}")
    return [dict(row, intent=float(row["intent"]), execution=float(row["execution"]),
                 complete=row["complete"] == "1", start=row.get("start", ""))
            for row in rows]


def holds_reported(path: Path) -> bool:
    """Whether a scores file keeps what a report needs (files written before it did not)."""
    try:
        with gzip.open(path, "rt") as text:
            return set(REPORTED) <= set(text.readline().strip().split(","))
    except (OSError, EOFError, UnicodeDecodeError) as error:
        raise RoboFollowError(f"{path}: not a scores file ({error})") from None


def compact_records(rows: list[dict]) -> list[dict]:
    """Episode records as a scores file keeps them: the fields of the full records that the
    summary, comparisons and reports read (what was done and the first failure worked out)."""
    return [_record(row) for row in rows]


def _record(row: dict) -> dict:
    task, _, round_part = row["episode"].partition("#")
    scene, level = task.split("/")[:2]
    record = {"episode": row["episode"], "scene": scene, "level": level, "task": task,
              "round": int(round_part.removeprefix("r") or 0), "motion": row["motion"] or None,
              "intent_score": row["intent"], "execution_score": row["execution"],
              "complete": row["complete"],
              "hashes": {"episode": row["hash"], "split": row["split"], "start": row["start"]}}
    if row.get("trajectory"):
        record["hashes"]["trajectory"] = row["trajectory"]
    if "did" not in row:  # written before the file kept what the report reads
        return record
    if row["chance_is"]:
        record["chance"] = {"IS": float(row["chance_is"]), "CR": float(row["chance_cr"])}
    record.update(
        layout=row["layout"], seed=int(row["seed"]) if row["seed"] else None,
        followed_intent=float(row["followed"]) if row["followed"] else None, did=row["did"],
        first_failure=(row["failed"], row["reason"]) if row["failed"] else None,
        clipped=int(row["clipped"] or 0), steps=int(row["steps"]) if row["steps"] else None,
        error=row["error"] or None, instruction=row["instruction"])
    if row.get("task_instruction"):
        record["task_instruction"] = row["task_instruction"]
    if row["video"]:
        record["video"] = row["video"]
    if row.get("observed"):
        record["observed"] = row["observed"].split(",")
    return record
