"""What a line of RUN/episodes.jsonl must hold: every field a reader hands on (the summary,
reports, comparisons, resume, merge, reproduce) is checked for its type and range, so that a
wrong one is a corrupt line naming the field, never a traceback further on.

The seven fields the summary reads of every record are required; the others are checked where
present (records of older runs, and the reports' hand-made ones, lack some)."""

from __future__ import annotations

from collections.abc import Callable

from robofollow.eval.running.scores import episode_problem
from robofollow.eval.statistics.metrics import MOTIONS
from robofollow.files import json_type, number_problem, shown

Check = Callable[[object], str | None]  # what is wrong with a value ("is 3, not text"), or None


def _text(value) -> str | None:
    return None if isinstance(value, str) else f"is {shown(value)}, not text"


def _flag(value) -> str | None:
    return None if isinstance(value, bool) else f"is {shown(value)}, not true or false"


def _whole(value) -> str | None:
    if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 2 ** 63:
        return None
    return f"is {shown(value)}, not a whole number from 0"


def _fraction(value) -> str | None:
    return number_problem(value, 0.0, 1.0)


def _non_negative(value) -> str | None:
    return number_problem(value, 0.0)


def _or_none(check: Check) -> Check:
    return lambda value: None if value is None else check(value)


def _one_of(*allowed) -> Check:
    return lambda value: None if value in allowed and not isinstance(value, bool) else (
        f"is {shown(value)}, not one of {', '.join(shown(a) for a in allowed)}")


def _list_of(check: Check) -> Check:
    def checked(value) -> str | None:
        if not isinstance(value, list):
            return f"is {shown(value)}, not a list"
        for index, item in enumerate(value):
            problem = check(item)
            if problem:
                return f"item {index + 1} {problem}"
        return None
    return checked


def _object(required: dict[str, Check], optional: dict[str, Check] | None = None,
            any_key: Check | None = None) -> Check:
    """An object with the `required` keys, perhaps the `optional` ones and, with `any_key`,
    any other key whose value passes it."""
    known = {**required, **(optional or {})}

    def checked(value) -> str | None:
        if not isinstance(value, dict):
            return f"is {shown(value)}, not an object"
        for key in required:
            if key not in value:
                return f"has no {key!r}"
        for key, item in value.items():
            check = known.get(key, any_key)
            if check is None:
                return f"has the unknown key {shown(key)}"
            problem = check(item)
            if problem:
                return f"{key!r} {problem}"
        return None
    return checked


_STAGE = _object({"stage": _text, "name": _text, "weight": _fraction, "intent": _fraction,
                  "execution": _fraction, "first_step": _or_none(_whole), "reason": _text})
_BEHAVIOUR = _object({}, {"description": _text, "match": _or_none(_text),
                          "behaviour": _or_none(_text), "intent_score": _fraction,
                          "execution_score": _fraction, "arms_moved": _or_none(_flag)})

REQUIRED = {"episode": _text, "scene": _text, "level": _text, "task": _text,
            "intent_score": _fraction, "execution_score": _fraction, "complete": _flag}
OPTIONAL = {
    "layout": _text, "round": _whole, "motion": _or_none(_one_of(*MOTIONS)),
    "seed": _or_none(_whole), "instruction": _text, "task_instruction": _text,
    "other_branch": _or_none(_flag), "stages": _list_of(_STAGE),
    "executed_behaviour": _or_none(_BEHAVIOUR), "steps": _or_none(_whole), "queries": _whole,
    "clipped": _whole, "error": _or_none(_text), "seconds": _non_negative,
    "observed": _list_of(_text), "hashes": _object({}, any_key=_text),
    "start_tolerance_m": _non_negative, "chance": _object({"IS": _fraction, "CR": _fraction}),
    "followed_intent": _or_none(_fraction), "video": _or_none(_text),
    "did": _text, "first_failure": _or_none(_list_of(_text)),
}
_RECORD = _object(REQUIRED, OPTIONAL, any_key=lambda value: None)  # (a newer field: kept)


def record_problem(record) -> str | None:
    """What is wrong with an episode record ("'hashes' 'start' is 3, not text"), or None:
    every field's type and range, the episode id's shape and its task, scene and level those
    of the record (the scores file's episode id checks, scores.py)."""
    if not isinstance(record, dict):
        return f"a JSON {json_type(record)}, not an episode record"
    problem = _RECORD(record)
    if problem:
        return problem.removeprefix("has ")
    problem = episode_problem(record["episode"])
    if problem:
        return f"'episode' {problem}"
    task = record["episode"].rpartition("#")[0]
    for key, value in zip(("task", "scene", "level"), (task, *task.split("/")[:2]), strict=True):
        if record[key] != value:
            return (f"{key!r} is {shown(record[key])}, but the episode id "
                    f"{shown(record['episode'])} says {shown(value)}")
    return None
