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
import re
import zlib
from pathlib import Path

from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError, did_you_mean, error_text
from robofollow.eval.running.outcomes import closest, first_failure
from robofollow.eval.statistics.metrics import MOTIONS
from robofollow.files import (
    not_utf8,
    number_problem,
    read_at_most,
    read_file_at_most,
    shown,
    write_bytes_atomic,
)

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


def scores_bytes(results: list[dict]) -> bytes:
    """The scores file of these records, as write_scores writes it."""
    text = io.StringIO()
    writer = csv.DictWriter(text, COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(score_rows(results))
    return gzip.compress(text.getvalue().encode(), mtime=0)


def write_scores(path: Path, results: list[dict]) -> None:
    write_bytes_atomic(path, scores_bytes(results))


MAX_UNPACKED = 64 * 1024 * 1024  # bytes a scores file may unpack to. The largest shipped one
#   (docs/results/expert-shuffled, 6350 episodes) unpacks to 3.0 MB, ~470 bytes an episode:
#   the cap holds some 140 000 episodes, and stops a small file that unpacks to gigabytes
SCENE_NAME = re.compile(r"[a-z][a-z0-9_]*")  # a scene's name (grammar/spec.lark: NAME)
_ROUND = re.compile(r"[1-9][0-9]{0,8}")
_WHOLE = re.compile(r"[0-9]{1,18}")  # a whole number from 0, as the writer writes it


class ScoresFileError(RoboFollowError):
    """A scores file that RoboFollow did not write as it stands (damaged, cut or edited)."""


def _names_problem(task: str) -> str | None:
    """What is wrong with the scene and level a task id of the right shape names, or None."""
    scene, level, _ = task.split("/", 2)
    if not SCENE_NAME.fullmatch(scene):
        return f"names the scene {shown(scene)}, not a scene name (a-z, 0-9, _)"
    if level not in LEVELS:
        return f"names the level {shown(level)}, not one of {', '.join(LEVELS)}"
    return None


def _task_shaped(task: str) -> bool:
    parts = task.split("/", 2)
    return len(parts) == 3 and all(parts) and "#" not in task


def task_problem(task) -> str | None:
    """What is wrong with a task id (scene/level/label: a scene name, a known level, a label),
    or None."""
    if not (isinstance(task, str) and _task_shaped(task)):
        return f"is {shown(task)}, not a task id (scene/level/label)"
    return _names_problem(task)


def episode_problem(episode) -> str | None:
    """What is wrong with an episode id (a task id, then #rN with a round from 1), or None."""
    task, _, round_part = episode.rpartition("#") if isinstance(episode, str) else ("", "", "")
    if not (_task_shaped(task) and round_part.startswith("r")):
        return f"is {shown(episode)}, not an episode id (scene/level/label#rN)"
    if not _ROUND.fullmatch(round_part[1:]):
        return f"ends in {shown('#' + round_part)}, not a round #rN (N from 1)"
    return _names_problem(task)


def _fraction(text: str) -> str | None:
    try:
        value = float(text)
    except ValueError:
        return f"is {shown(text)}, not a number"
    return number_problem(value, 0.0, 1.0)


def _whole(text: str) -> str | None:
    return None if _WHOLE.fullmatch(text) else f"is {shown(text)}, not a whole number from 0"


def _optional(check):
    return lambda text: None if text == "" else check(text)


def _one_of(*allowed: str):
    return lambda text: None if text in allowed else (
        f"is {shown(text)}, not one of {', '.join(shown(a) for a in allowed)}")


# what each column must hold (the others hold any text)
_CHECKS = {"episode": episode_problem, "intent": _fraction, "execution": _fraction,
           "complete": _one_of("0", "1"), "motion": _one_of("", *MOTIONS),
           "seed": _optional(_whole), "chance_is": _optional(_fraction),
           "chance_cr": _optional(_fraction), "followed": _optional(_fraction),
           "clipped": _optional(_whole), "steps": _optional(_whole)}


def _unpacked(path: Path) -> str:
    """The file's text, unpacked up to MAX_UNPACKED bytes."""
    packed, problem = read_file_at_most(path, MAX_UNPACKED)
    if problem:
        raise ScoresFileError(f"{path}: {problem}")
    try:
        with gzip.GzipFile(fileobj=io.BytesIO(packed)) as stream:
            data = read_at_most(stream, MAX_UNPACKED)
    except (OSError, EOFError, zlib.error) as error:
        raise ScoresFileError(f"{path}: not a scores file ({error_text(error)})") from None
    if data is None:
        raise ScoresFileError(f"{path}: unpacks to more than {MAX_UNPACKED >> 20} MiB; not a "
                              "scores file RoboFollow wrote")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        line, column, _, _ = not_utf8(data, error)
        raise ScoresFileError(f"{path}: line {line}, column {column}: not UTF-8 text (byte "
                              f"0x{data[error.start]:02x})") from None


def _header(path: Path, header: list[str]) -> None:
    """The header names known columns, once each, the first seven and, with `did`, all that a
    report reads."""
    for index, name in enumerate(header):
        if name not in COLUMNS:
            hint = did_you_mean(name, COLUMNS)
            raise ScoresFileError(f"{path}: line 1: unknown column {shown(name)}"
                                  f"{'; ' + hint if hint else ''}")
        if name in header[:index]:
            raise ScoresFileError(f"{path}: line 1: the column {name} appears twice")
    needed = COLUMNS[:7] + (REPORTED if "did" in header else ())
    lacking = [name for name in needed if name not in header]
    if lacking:
        raise ScoresFileError(f"{path}: line 1: lacks the columns {', '.join(lacking)}")


def _rows(path: Path, header_only: bool = False) -> tuple[list[str], list[dict]]:
    """The header and rows of a scores file (no rows with `header_only`), each row checked:
    the field count, each column's value (_CHECKS), chance IS and CR together, and each
    episode once."""
    reader = csv.reader(io.StringIO(_unpacked(path)))
    rows, seen = [], {}
    try:
        header = next(reader, None)
        if not header:
            raise ScoresFileError(f"{path}: line 1: no header (an empty file)")
        _header(path, header)
        if header_only:
            return header, []
        checks = [(index, name, _CHECKS[name]) for index, name in enumerate(header)
                  if name in _CHECKS]
        for fields in reader:
            if not fields:
                continue  # a blank line
            line = reader.line_num
            if len(fields) != len(header):
                raise ScoresFileError(f"{path}: line {line}: {len(fields)} fields, but the "
                                      f"header names {len(header)}")
            for index, name, check in checks:
                problem = check(fields[index])
                if problem:
                    raise ScoresFileError(f"{path}: line {line}: {name} {problem}")
            row = dict(zip(header, fields, strict=True))
            if (row.get("chance_is", "") == "") != (row.get("chance_cr", "") == ""):
                raise ScoresFileError(f"{path}: line {line}: chance_is and chance_cr: one is "
                                      "empty, the other not")
            episode = row["episode"]
            if episode in seen:
                raise ScoresFileError(f"{path}: line {line}: episode {shown(episode)} is also "
                                      f"on line {seen[episode]}")
            seen[episode] = line
            rows.append(row)
    except csv.Error as error:
        raise ScoresFileError(f"{path}: line {reader.line_num}: not CSV ({error})") from None
    return header, rows


def read_scores(path: Path) -> list[dict]:
    """The rows of a scores file, checked (ScoresFileError names the line and column of what
    is wrong): intent and execution as floats, complete as a bool."""
    return [dict(row, intent=float(row["intent"]), execution=float(row["execution"]),
                 complete=row["complete"] == "1", start=row.get("start", ""))
            for row in _rows(path)[1]]


def holds_reported(path: Path) -> bool:
    """Whether a scores file keeps what a report needs (files written before it did not); its
    header is checked as read_scores checks it."""
    return set(REPORTED) <= set(_rows(path, header_only=True)[0])


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
