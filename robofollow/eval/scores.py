"""RUN/scores.csv.gz: every episode's scores in a compact file a run keeps (and the reference
runs in docs/results commit), so that later runs compare against it episode by episode: the
episode id, its hash (what pairs two runs' episodes), its scene's split digest, the task's
motion, Intent, Execution, completion and the hash of its realised start on a grid
(runner.start_hash; files written before it lack that column). Byte-identical for the same
records."""

from __future__ import annotations

import csv
import gzip
import io
from pathlib import Path

from robofollow.errors import RoboFollowError
from robofollow.files import write_bytes_atomic

SCORES = "scores.csv.gz"
COLUMNS = ("episode", "hash", "split", "motion", "intent", "execution", "complete", "start")
_LATER = ("start",)  # columns that files written before them lack


def score_rows(results: list[dict]) -> list[dict]:
    """One row per record, in episode order."""
    return [{"episode": r["episode"], "hash": r.get("hashes", {}).get("episode", ""),
             "split": r.get("hashes", {}).get("split", ""), "motion": r.get("motion") or "",
             "intent": f"{r['intent_score']:.4f}", "execution": f"{r['execution_score']:.4f}",
             "complete": int(bool(r["complete"])),
             "start": r.get("hashes", {}).get("start", "")}
            for r in sorted(results, key=lambda r: r["episode"])]


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
    lacking = sorted(set(COLUMNS) - set(_LATER) - set(rows[0])) if rows else []
    if lacking:
        raise RoboFollowError(f"{path}: lacks the columns {', '.join(lacking)}")
    return [dict(row, intent=float(row["intent"]), execution=float(row["execution"]),
                 complete=row["complete"] == "1", start=row.get("start", ""))
            for row in rows]
