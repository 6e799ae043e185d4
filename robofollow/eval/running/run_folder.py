"""The run folder on disk: RUN/run.json, RUN/episodes.jsonl (whole lines appended, read back
with their corrupt lines), RUN/summary.json and the lock that keeps one run in a folder.
Every failure is a RoboFollowError that says what and where; nothing is lost."""

from __future__ import annotations

import errno
import fcntl
import json
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from robofollow import release
from robofollow.errors import RoboFollowError, UsageError
from robofollow.files import (
    changed_options,
    json_line,
    json_lines,
    read_json_file,
    write_bytes_atomic,
    write_json_atomic,
)
from robofollow.provenance import differences

RUN_FILE, RESULTS, SUMMARY, LOCK = "run.json", "episodes.jsonl", "summary.json", ".lock"
SCORES = "scores.csv.gz"  # the compact records a finished run keeps (scores.py)
MAX_JSON_BYTES = 16 * 1024 * 1024  # run.json and summary.json: the shipped ones are under 1 KB
#   and 10 KB; a run that lists every task of the benchmark (--tasks) stays under 100 KB
DROPPED = RESULTS + ".dropped"  # corrupt lines that --drop-corrupt moved out of RESULTS
_RECORD_FIELDS = {"episode": str, "scene": str, "level": str, "task": str,
                  "intent_score": (int, float), "execution_score": (int, float),
                  "complete": bool}  # what the summary reads of every record; _record_problem
#   checks them: Intent and Execution from 0 to 1, the episode id's shape (scores.py:
#   episode_problem) and its task, scene and level those of the record


class EvalRunError(RoboFollowError):
    """The run folder cannot be used as asked (or the run cannot go on)."""


class EvalOutputError(EvalRunError):
    """An output path that cannot be written."""


class RunInUseError(EvalRunError):
    """Another run holds the run folder."""


class CorruptResultsError(EvalRunError):
    """Lines of RUN/episodes.jsonl that are not whole episode records."""

    def __init__(self, path: Path, problems: list[tuple[int, str]]):
        shown = "; ".join(f"line {number}: {why}" for number, why in problems[:5])
        more = f" (and {len(problems) - 5} more)" if len(problems) > 5 else ""
        count = f"{len(problems)} corrupt line{'s' if len(problems) != 1 else ''}"
        super().__init__(
            f"{path} has {count}: {shown}{more}. `robofollow eval` with the run's options "
            f"and --resume --drop-corrupt moves such lines to {path.with_name(DROPPED)} and "
            "evaluates again the episodes left without a record")
        self.path, self.problems = path, problems


RESUMABLE = ("; the finished episodes are kept: fix it and run the same command with --resume "
             "to continue")


def _record_problem(record) -> str | None:
    if not isinstance(record, dict):
        return f"a JSON {type(record).__name__}, not an episode record"
    for key, kind in _RECORD_FIELDS.items():
        if key not in record:
            return f"no {key!r}"
        if not isinstance(record[key], kind) or (kind != bool and isinstance(record[key], bool)):
            return f"{key!r} is {json.dumps(record[key])[:40]}"
    # (imported here: the record's checks are the scores file's, scores.py)
    from robofollow.eval.running.scores import episode_problem
    from robofollow.files import number_problem, shown
    for key in ("intent_score", "execution_score"):
        problem = number_problem(record[key], 0.0, 1.0)
        if problem:
            return f"{key!r} {problem}"
    problem = episode_problem(record["episode"])
    if problem:
        return f"'episode' {problem}"
    task = record["episode"].rpartition("#")[0]
    for key, value in zip(("task", "scene", "level"), (task, *task.split("/")[:2]), strict=True):
        if record[key] != value:
            return (f"{key!r} is {shown(record[key])}, but the episode id "
                    f"{shown(record['episode'])} says {shown(value)}")
    return None


def _scan(path: Path) -> tuple[list[dict], list[bytes], list[tuple[int, bytes, str]]]:
    """The whole records of a results file, their lines, and its corrupt lines (number, line,
    what is wrong). Lines end at "\\n" only; a last line cut short by a kill is removed from
    the file."""
    if not path.is_file():
        return [], [], []
    data = path.read_bytes()
    whole = data[:data.rfind(b"\n") + 1]
    if len(whole) != len(data):
        with open(path, "r+b") as f:
            f.truncate(len(whole))
    records, lines, corrupt, seen = [], [], [], {}
    for line in json_lines(whole):
        record = line.value
        why = line.problem or _record_problem(record)
        if why is None and record["episode"] in seen:
            why = f"repeats episode {record['episode']} of line {seen[record['episode']]}"
        if why is not None:
            corrupt.append((line.number, line.raw, why))
            continue
        seen[record["episode"]] = line.number
        records.append(record)
        lines.append(line.raw)
    return records, lines, corrupt


def read_results(path: Path) -> list[dict]:
    """The finished episodes; a last line cut short by a kill is removed from the file, and a
    corrupt line raises CorruptResultsError (with its line number and what is wrong)."""
    records, _, corrupt = _scan(path)
    if corrupt:
        raise CorruptResultsError(path, [(number, why) for number, _, why in corrupt])
    return records


def drop_corrupt_lines(path: Path) -> list[dict]:
    """Move the corrupt lines of a results file to its side file (appended, nothing is
    lost), keep the whole records; returns them."""
    records, lines, corrupt = _scan(path)
    if not corrupt:
        return records
    side = safe_path(path.parent, DROPPED)
    partial_file = safe_path(path.parent, path.name + ".partial")
    try:
        with open(side, "ab") as f:
            f.writelines(line + b"\n" for _, line, _ in corrupt)
            f.flush()
            os.fsync(f.fileno())
        partial_file.write_bytes(b"".join(line + b"\n" for line in lines))
        os.replace(partial_file, path)
    except OSError as error:
        raise EvalOutputError(f"cannot drop the corrupt lines of {path}: "
                              f"{error.strerror or error}") from None
    numbers = ", ".join(str(number) for number, _, _ in corrupt[:10])
    print(f"dropped {len(corrupt)} corrupt line{'s' if len(corrupt) != 1 else ''} of {path} "
          f"(line {numbers}{' …' if len(corrupt) > 10 else ''}); they are kept in {side}",
          file=sys.stderr)
    return records


class ResultsFile:
    """RUN/episodes.jsonl, open for appending whole lines. A write that fails (a full disk) is
    cut back to the last whole line and stops the run with EvalOutputError."""

    def __init__(self, path: Path):
        self.path = path
        try:
            self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW,
                              0o644)
        except OSError as error:
            raise EvalOutputError(f"cannot write {path}: {error.strerror or error}") from None

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[os.write(self.fd, view):]

    def append(self, record: dict) -> None:
        data = json_line(record).encode("utf-8")
        end = os.lseek(self.fd, 0, os.SEEK_END)
        try:
            self.write(data)
        except OSError as error:
            with suppress(OSError):
                os.ftruncate(self.fd, end)  # whole lines only
            raise EvalOutputError(f"cannot write {self.path}: {error.strerror or error}"
                                  f"{RESUMABLE}") from None

    def close(self) -> None:
        os.close(self.fd)

    def __enter__(self) -> "ResultsFile":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _holds_files(out: Path) -> bool:
    return out.is_dir() and any(p.name != LOCK for p in out.iterdir())


def check_out(out: Path) -> None:
    """Why the run folder cannot be used, said before anything is written."""
    try:
        if out.exists() and not out.is_dir():
            raise EvalOutputError(f"the run folder {out} is a file; choose a folder (new or "
                                  "holding a run to resume)")
        existing = next(p for p in (out, *out.parents) if p.exists())
        if not existing.is_dir():
            raise EvalOutputError(f"cannot create the run folder {out}: {existing} is a file")
        if not os.access(existing, os.W_OK | os.X_OK):
            raise EvalOutputError(f"cannot write in {existing}: permission denied")
        if not (out / RUN_FILE).is_file() and _holds_files(out):
            raise EvalRunError(f"{out} is not empty and holds no run")
    except OSError as error:
        raise EvalOutputError(f"cannot use the run folder {out}: "
                              f"{error.strerror or error}") from None


@contextmanager
def run_lock(out: Path) -> Iterator[None]:
    """Hold RUN/.lock (made with its folder) for the block; RunInUseError at once if another
    process holds it. flock goes with its process, so a killed run's lock never blocks."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        fd = os.open(safe_path(out, LOCK), os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    except OSError as error:
        raise EvalOutputError(f"cannot write in the run folder {out}: "
                              f"{error.strerror or error}") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            if error.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise EvalOutputError(f"cannot lock {out / LOCK}: {error.strerror}") from None
            holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
            by = f" (process {holder})" if holder.isdigit() else ""
            raise RunInUseError(f"{out} is in use by another robofollow eval{by}; wait for it "
                                "to end, or choose another folder") from None
        with suppress(OSError):  # (only to name the holder)
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        os.close(fd)


def write_json(path: Path, data) -> None:
    try:
        write_json_atomic(path, data)
    except OSError as error:
        raise EvalOutputError(f"cannot write {path}: {error.strerror or error}"
                              f"{RESUMABLE}") from None


def _unstarted(out: Path) -> bool:
    """A run folder whose run never finished an episode (a run stopped before its first, or a
    mistyped command's): as good as empty. A folder that keeps a finished run's summary or
    scores (a shipped run) is not."""
    results = out / RESULTS
    return ((out / RUN_FILE).is_file()
            and (not results.is_file() or results.stat().st_size == 0)
            and not (out / SUMMARY).exists() and not (out / SCORES).exists())


def finished(out: Path) -> bool:
    """Whether the folder keeps a finished run's results: its summary and scores."""
    return (out / SUMMARY).is_file() and (out / SCORES).is_file()


def _lines(path: Path) -> int:
    """How many lines a file holds, read in blocks."""
    count = 0
    with open(path, "rb") as stream:
        while block := stream.read(1 << 20):
            count += block.count(b"\n")
    return count


def _summarised(out: Path) -> int | None:
    """The episodes a run's summary counts (None: no summary, or one that does not say)."""
    if not (out / SUMMARY).is_file():
        return None
    data, problem = read_json_file(out / SUMMARY, MAX_JSON_BYTES)
    count = data.get("episodes") if isinstance(data, dict) and not problem else None
    return count if isinstance(count, int) and not isinstance(count, bool) else None


def check_whole(out: Path) -> None:
    """EvalRunError for a finished run whose results file holds fewer lines than its summary
    counts episodes (an emptied or replaced file): resuming it would run its episodes again
    over its scores. (Corrupt lines count: --drop-corrupt repairs those.)"""
    if not (finished(out) and (out / RESULTS).is_file()):
        return
    kept, counted = _lines(out / RESULTS), _summarised(out)
    if counted is not None and kept < counted:
        raise EvalRunError(f"{out} holds a finished run whose {RESULTS} keeps {kept} of the "
                           f"{counted} episodes its summary counts; it is not resumed (its "
                           "episodes would run again over its scores): choose another folder")


def check_prepare(out: Path, options: dict, resume: bool) -> None:
    """Why the run folder cannot take this run (new, or resumed with the same options), said
    before anything is written. A run that keeps only its scores (as docs/results' do) is
    never resumed: its episodes could not be told from new ones."""
    check_out(out)
    run_file = out / RUN_FILE
    if not run_file.is_file() or _unstarted(out):
        return
    try:
        previous = json.loads(run_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        raise EvalRunError(f"{run_file} cannot be read: {error}") from None
    if not resume:
        raise EvalRunError(f"{out} already holds a run; pass --resume to continue it, or "
                           "choose another folder")
    if not (out / RESULTS).is_file():
        raise EvalRunError(f"{out} holds a finished run that keeps only its scores "
                           f"({SCORES}, no {RESULTS}); it cannot be resumed or written over: "
                           "choose another folder")

    problem = changed_options(_named_release(previous) if isinstance(previous, dict) else {},
                              _named_release(options))
    if problem:
        raise EvalRunError(f"{out} {problem}")


def _named_release(recorded: dict) -> dict:
    """A run's options as a run of today records them: one made before runs named their
    release gets the release its specs were frozen as (so that it resumes on it)."""
    if "release" in recorded or "specs" in recorded:
        return recorded
    name = release.of_spec_digest(str(recorded.get("spec_digest")))
    if name is None:
        return recorded
    return dict(recorded, release=name, release_digest=release.manifest(name).digest)


def prepare(out: Path, options: dict, resume: bool, environment: dict | None) -> None:
    """Record a new run's options and the environment that runs it (a folder with no
    finished episode counts as new), or check that a resumed run has the same options; a
    resume in another environment is said, naming what differs, and added to the run's
    provenance (`environment` None: a resume that runs nothing, which adds none)."""
    check_prepare(out, options, resume)
    run_file = safe_path(out, RUN_FILE)
    if not run_file.is_file() or _unstarted(out):
        write_json(run_file, dict(options, provenance=[environment]))
        return
    if environment is None:  # (a resume that runs nothing adds no environment)
        return
    recorded = json.loads(run_file.read_text(encoding="utf-8"))  # (an object: check_prepare)
    made = recorded.get("provenance") or []
    if not (isinstance(made, list) and all(isinstance(entry, dict) for entry in made)):
        raise EvalRunError(f"{run_file}: provenance is not a list of objects")
    if environment in made:
        return
    if made:
        print(f"warning: {out} is resumed in another environment than it was started in "
              f"({'; '.join(differences(made[-1], environment))}): its trajectory hashes "
              "will not all be comparable with one environment's", file=sys.stderr)
    write_json(run_file, dict(recorded, provenance=[*made, environment]))


def check_folder_out(out: Path) -> None:
    """An --out folder that cannot hold results (a file, or under one) is a bad argument."""
    blocking = next((p for p in (out, *out.parents) if p.exists()), None)
    if blocking is not None and not blocking.is_dir():
        raise UsageError(f"--out {out}: {blocking} is a file; give a folder")


def write_text_file(path: Path, text: str) -> None:
    """A text file written whole (atomically), or EvalOutputError saying why not."""
    try:
        write_bytes_atomic(path, text.encode("utf-8"))
    except OSError as error:
        raise EvalOutputError(f"cannot write {path}: {error.strerror or error}") from None


def safe_path(out: Path, *parts: str) -> Path:
    """out/parts, refused where it or a folder on the way below `out` is a symbolic link: no
    write follows a link out of a run folder (or any --out)."""
    path = out
    for part in parts:
        path = path / part
        if path.is_symlink():
            raise EvalOutputError(f"{path} is a symbolic link; RoboFollow writes only inside "
                                  f"{out} and never through a link: remove it, or choose "
                                  "another folder")
    return path


CONTROLS = "controls"  # RUN/controls/<instruction mode>: a run's control arms


def control_arms(run: Path) -> list[str]:
    """The modes of the run's control arms (RUN/controls/<mode> holding a run), sorted;
    EvalOutputError where RUN/controls or an arm is a symbolic link (a run's arms live
    inside it: nothing is read or written through a link)."""
    folder = safe_path(run, CONTROLS)
    if not folder.is_dir():
        return []
    return sorted(arm.name for arm in folder.iterdir()
                  if (safe_path(run, CONTROLS, arm.name) / RUN_FILE).is_file())
