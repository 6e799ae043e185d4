"""A finished run read back: its options (RUN/run.json) and its episodes, from the full
records (RUN/episodes.jsonl) or, where a run keeps only those (the runs docs/results ships),
the compact records of its score file (RUN/scores.csv.gz).

Every file is checked as it is read: a bad one is a RunReadError (or the scores file's
ScoresFileError, or the results file's CorruptResultsError) on one line that names the file,
the field (and the line, where the file has lines) and what is wrong."""

from __future__ import annotations

import json
import math
import re
from dataclasses import MISSING, fields
from pathlib import Path

from pydantic import TypeAdapter, ValidationError

from robofollow import release
from robofollow.compiler.scene.spec import LEVELS
from robofollow.errors import RoboFollowError, did_you_mean
from robofollow.eval.running.modes import INSTRUCTION_MODES, VIDEO_MODES
from robofollow.eval.running.run_folder import (
    RESULTS,
    RUN_FILE,
    SCORES,
    RunReadError,
    present,
    read_results,
    read_run_object,
)
from robofollow.eval.running.runner import EvalOptions, shard_of
from robofollow.eval.running.scores import (
    SCENE_NAME,
    compact_records,
    holds_reported,
    read_scores,
    task_problem,
)
from robofollow.files import json_type, key_problem, shown
from robofollow.provenance import FIELDS as PROVENANCE_FIELDS
from robofollow.provenance import NOTE

PROVENANCE = "provenance"  # what run.json records beside the options: the environments
_OPTIONS = fields(EvalOptions)
_REQUIRED = tuple(f.name for f in _OPTIONS
                  if f.default is MISSING and f.default_factory is MISSING)
_OPTIONAL = (*(f.name for f in _OPTIONS if f.name not in _REQUIRED), PROVENANCE)
_ADAPTER = TypeAdapter(EvalOptions)
_DIGEST = re.compile(r"[0-9a-f]{64}")  # a spec digest: sha256, in hex


def _keys(path: Path, data: dict, required, optional, where: str = "") -> None:
    """RunReadError for the first key the object lacks or does not know."""
    found = key_problem(data, required, optional)
    if found is None:
        return
    kind, key = found
    if kind == "missing":
        raise RunReadError(f"{path}: {where}no {shown(key)}")
    hint = did_you_mean(key, (*required, *optional))
    raise RunReadError(f"{path}: {where}unknown key {shown(key)}{'; ' + hint if hint else ''}")


def _typed(path: Path, data: dict) -> EvalOptions:
    """The options as their types say (EvalOptions' fields; JSON arrays for tuples)."""
    try:
        return _ADAPTER.validate_json(json.dumps(data), strict=True)
    except ValidationError as error:
        first = error.errors()[0]
        where = ".".join(map(str, first["loc"]))
        message = first["msg"][:1].lower() + first["msg"][1:]
        raise RunReadError(f"{path}: {where} is {shown(first['input'])}: {message}") from None


def _options_problem(options: EvalOptions) -> str | None:
    """What is wrong with well-typed options (`field` first), or None."""
    for index, scene in enumerate(options.scenes):
        if not SCENE_NAME.fullmatch(scene):
            return f"scenes[{index}] is {shown(scene)}, not a scene name (a-z, 0-9, _)"
    for index, level in enumerate(options.levels):
        if level not in LEVELS:
            hint = did_you_mean(level, LEVELS)
            return (f"levels[{index}] is {shown(level)}, not one of {', '.join(LEVELS)}"
                    f"{'; ' + hint if hint else ''}")
    if not options.scenes or not options.levels:
        return f"{'scenes' if not options.scenes else 'levels'} is empty"
    for index, task in enumerate(options.tasks):
        problem = task_problem(task)
        if problem:
            return f"tasks[{index}] {problem}"
    modes = {"instruction_mode": (options.instruction_mode, INSTRUCTION_MODES),
             "video": (options.video, VIDEO_MODES)}
    for index, mode in enumerate(getattr(options, "controls", ())):
        modes[f"controls[{index}]"] = (mode, INSTRUCTION_MODES)
    for field, (value, known) in modes.items():
        if value not in known:
            return f"{field} is {shown(value)}, not one of {', '.join(known)}"
    if not _DIGEST.fullmatch(options.spec_digest):
        return f"spec_digest is {shown(options.spec_digest)}, not a sha256 digest (64 hex digits)"
    problem = _release_problem(options)
    if problem:
        return problem
    for field in ("rounds", "sample"):
        value = getattr(options, field)
        if value is not None and value < 1:
            return f"{field} is {value}, not at least 1"
    timeout = options.policy_timeout
    if timeout is not None and not (math.isfinite(timeout) and timeout > 0):
        return f"policy_timeout is {timeout}, not a number of seconds above 0"
    return None


def _release_problem(options: EvalOptions) -> str | None:
    """What is wrong with the release a run names (`field` first): one this RoboFollow does not
    ship, a digest that is not its, a digest without a release, or a release beside specs."""
    if options.release is None:
        if options.release_digest is not None:
            return "release_digest is given, but no release"
        return None
    if options.specs is not None:
        return "release and specs are both given: a run reads a release or a working compile"
    known = release.names()
    if options.release not in known:
        hint = did_you_mean(options.release, known)
        return (f"release is {shown(options.release)}, which this RoboFollow does not ship "
                f"(releases: {', '.join(known) or 'none'}){'; ' + hint if hint else ''}")
    digest = release.manifest(options.release).digest
    if options.release_digest not in (None, digest):
        return (f"release_digest is {shown(options.release_digest)}, not release "
                f"{options.release}'s ({digest[:16]}...)")
    return None


def _provenance(path: Path, entries) -> list[dict]:
    """run.json's provenance: a list of objects whose keys are provenance.FIELDS (and NOTE)
    and whose values are strings or null."""
    if not isinstance(entries, list):
        raise RunReadError(f"{path}: {PROVENANCE} is a JSON {json_type(entries)}, not an array")
    for index, entry in enumerate(entries):
        where = f"{PROVENANCE}[{index}]"
        if not isinstance(entry, dict):
            raise RunReadError(f"{path}: {where} is a JSON {json_type(entry)}, not an object")
        _keys(path, entry, (), (*PROVENANCE_FIELDS, NOTE), f"{where}: ")
        for key, value in entry.items():
            if value is not None and not isinstance(value, str):
                raise RunReadError(f"{path}: {where}.{key} is {shown(value)}, not a string or "
                                   "null")
    return [dict(entry) for entry in entries]


def read_run_file(run: Path) -> tuple[EvalOptions, list[dict]]:
    """The options RUN/run.json records, checked (exactly EvalOptions' fields, those with a
    default optional, of their types and in range), and its provenance (empty where it records
    none)."""
    path = run / RUN_FILE
    data = read_run_object(path, "a run's options")
    _keys(path, data, _REQUIRED, _OPTIONAL)
    provenance = _provenance(path, data[PROVENANCE]) if PROVENANCE in data else []
    options = _typed(path, {k: v for k, v in data.items() if k != PROVENANCE})
    problem = _options_problem(options)
    if problem:
        raise RunReadError(f"{path}: {problem}")
    if options.shard is not None:
        try:
            shard_of(options.shard)
        except RoboFollowError as error:
            raise RunReadError(f"{path}: {error}") from None
    return options, provenance


def load_options(run: Path) -> EvalOptions:
    if not present(run / RUN_FILE):
        what = "no such folder" if not run.is_dir() else f"no {RUN_FILE}"
        raise RunReadError(f"{run} holds no evaluation run ({what})")
    return read_run_file(run)[0]


def load_provenance(run: Path) -> list[dict]:
    """The environments that ran the run (RUN/run.json's provenance: one entry per environment,
    provenance.FIELDS); empty where it records none, or keeps no run.json (a folder of scores
    only)."""
    if not present(run / RUN_FILE):
        return []
    return read_run_file(run)[1]


def load_records(run: Path, reported: bool = False) -> list[dict]:
    """The run's episode records: full where it keeps them, else compact. `reported`: the
    records must hold what a report reads (a score file written before it kept that does
    not)."""
    if present(run / RESULTS):
        return read_results(run / RESULTS)
    if present(run / SCORES):
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
