"""`robofollow vqa score`: a file of answers graded against the probe's expected answers.

Each line of ANSWERS.jsonl is {"id", "prediction"} plus, if the line does not carry it, the
question's "expected" is looked up by id in the questions file (default: questions.jsonl next
to ANSWERS.jsonl), so a copy of questions.jsonl with a "prediction" added to each line works.
"""

from __future__ import annotations

import os
from collections import defaultdict
from pathlib import Path

from pydantic import ValidationError

from robofollow.errors import RoboFollowError
from robofollow.files import json_lines, read_file_at_most, shown
from robofollow.vqa.answers import Expected
from robofollow.vqa.score import score

MAX_ANSWERS_BYTES = 256 * 1024 * 1024  # ANSWERS.jsonl or questions.jsonl: about 1 KB a
#   question (the QA-20 probe's questions.jsonl: 20 KB)


class GradeError(RoboFollowError):
    """An answers file that cannot be graded."""


def _read_jsonl(path: Path) -> list[tuple[int, dict]]:
    """(line number, record) of each line: an object whose "id" is a string."""
    data, problem = read_file_at_most(path, MAX_ANSWERS_BYTES)
    if problem:
        raise GradeError(f"{path}: {problem}")
    records = []
    for line in json_lines(data):
        if line.problem:
            raise GradeError(f"{path}:{line.number}:{line.column}: {line.problem}")
        if not isinstance(line.value, dict):
            raise GradeError(f"{path}:{line.number}: expected an object per line")
        if not isinstance(line.value.get("id"), str):
            raise GradeError(f"{path}:{line.number}: id is {shown(line.value.get('id'))}, "
                             "not a string")
        records.append((line.number, line.value))
    return records


def _expected(where: str, question: dict) -> Expected:
    """The question's expected answer; else GradeError at `where`, naming the field."""
    try:
        return Expected.model_validate(question.get("expected"))
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(map(str, ("expected", *first["loc"])))
        raise GradeError(f"{where}: {field} is {shown(first['input'])}: {first['msg']}"
                         ) from None


def grade(answers: Path, questions: Path | None = None) -> dict:
    """{"correct", "total", "templates": {template: [correct, total]}, "results": [...]}."""
    known: dict[str, tuple[str, dict]] = {}  # id -> (file:line, question)
    given, questions = questions is not None, questions or answers.parent / "questions.jsonl"
    same = os.path.realpath(questions) == os.path.realpath(answers)  # (never raises)
    if (given or questions.is_file()) and not same:
        known = {r["id"]: (f"{questions}:{n}", r) for n, r in _read_jsonl(questions)}
    results, templates = [], defaultdict(lambda: [0, 0])
    for number, record in _read_jsonl(answers):
        where = f"{answers}:{number}"
        if "prediction" not in record:
            raise GradeError(f"{where}: each line needs \"id\" and \"prediction\"")
        at, question = ((where, record) if "expected" in record else
                        known.get(record["id"], (where, None)))
        if question is None:
            raise GradeError(f"{where}: question {record['id']!r} is not in {questions}")
        expected = _expected(at, question)
        verdict = score(str(record["prediction"]), expected)
        results.append({"id": record["id"], "question": question.get("question", ""),
                        "prediction": record["prediction"], "answer": expected.text,
                        "correct": verdict.correct, "reason": verdict.reason})
        tally = templates[expected.template or "other"]
        tally[0] += verdict.correct
        tally[1] += 1
    return {"correct": sum(r["correct"] for r in results), "total": len(results),
            "templates": dict(templates), "results": results}


def grade_text(graded: dict) -> str:
    lines = []
    for result in graded["results"]:
        if not result["correct"]:
            lines += [f"✗ {result['id']}: {result['question']}",
                      f"    answered: {result['prediction']}",
                      f"    {result['reason']}"]
    total = graded["total"]
    share = 100 * graded["correct"] / total if total else 0.0
    lines.append(f"{graded['correct']}/{total} correct ({share:.1f}%)")
    lines += [f"  {template:<11} {right}/{count}"
              for template, (right, count) in sorted(graded["templates"].items())]
    return "\n".join(lines)
