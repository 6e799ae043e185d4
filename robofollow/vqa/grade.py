"""`robofollow vqa score`: a file of answers graded against the probe's expected answers.

Each line of ANSWERS.jsonl is {"id", "prediction"} plus, if the line does not carry it, the
question's "expected" is looked up by id in the questions file (default: questions.jsonl next
to ANSWERS.jsonl), so a copy of questions.jsonl with a "prediction" added to each line works.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

from robofollow.errors import RoboFollowError
from robofollow.files import json_lines
from robofollow.vqa.answers import Expected
from robofollow.vqa.score import score


class GradeError(RoboFollowError):
    """An answers file that cannot be graded."""


def _read_jsonl(path: Path) -> list[tuple[int, dict]]:
    try:
        data = path.read_bytes()
    except OSError as error:
        raise GradeError(f"cannot read {path}: {error.strerror}") from None
    records = []
    for line in json_lines(data):
        if line.problem:
            raise GradeError(f"{path}:{line.number}:{line.column}: {line.problem}")
        if not isinstance(line.value, dict):
            raise GradeError(f"{path}:{line.number}: expected an object per line")
        records.append((line.number, line.value))
    return records


def grade(answers: Path, questions: Path | None = None) -> dict:
    """{"correct", "total", "templates": {template: [correct, total]}, "results": [...]}."""
    known: dict[str, dict] = {}
    questions = questions or answers.parent / "questions.jsonl"
    if questions.is_file() and questions.resolve() != answers.resolve():
        known = {r["id"]: r for _, r in _read_jsonl(questions)}
    results, templates = [], defaultdict(lambda: [0, 0])
    for number, record in _read_jsonl(answers):
        where = f"{answers}:{number}"
        if "prediction" not in record or "id" not in record:
            raise GradeError(f"{where}: each line needs \"id\" and \"prediction\"")
        question = record if "expected" in record else known.get(record["id"])
        if question is None:
            raise GradeError(f"{where}: question {record['id']!r} is not in {questions}")
        expected = Expected.model_validate(question["expected"])
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
