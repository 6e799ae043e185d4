"""The run folder on disk: RUN/run.json, RUN/episodes.jsonl (whole lines appended, read back
with their corrupt lines), RUN/summary.json and the lock that keeps one run in a folder.
Every failure is a RoboFollowError that says what and where; nothing is lost."""

from __future__ import annotations

import errno
import fcntl
import os
import stat
import sys
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from robofollow import release
from robofollow.errors import RoboFollowError, UsageError
from robofollow.eval.running.episode_record import record_problem
from robofollow.files import (
    changed_options,
    file_problem,
    json_line,
    json_lines,
    not_regular,
    read_file_at_most,
    read_json_object,
    shown,
    write_bytes_atomic,
    write_json_atomic,
)
from robofollow.provenance import differences

RUN_FILE, RESULTS, SUMMARY, LOCK = "run.json", "episodes.jsonl", "summary.json", ".lock"
SCORES = "scores.csv.gz"  # the compact records a finished run keeps (scores.py)
MAX_JSON_BYTES = 16 * 1024 * 1024  # run.json and summary.json: the shipped ones are under 1 KB
#   and 10 KB; a run that lists every task of the benchmark (--tasks) stays under 100 KB
MAX_RESULTS_BYTES = 256 * 1024 * 1024  # RUN/episodes.jsonl: a record takes about 1.6 KB, so a
#   whole benchmark's round (6,350 episodes) about 10 MB; this holds some 25 rounds
DROPPED = RESULTS + ".dropped"  # corrupt lines that --drop-corrupt moved out of RESULTS


class EvalRunError(RoboFollowError):
    """The run folder cannot be used as asked (or the run cannot go on)."""


class EvalOutputError(EvalRunError):
    """An output path that cannot be written."""


class RunInUseError(EvalRunError):
    """Another run holds the run folder."""


class RunReadError(EvalRunError):
    """A folder that holds no evaluation run, or not the part of one that is asked for, or a
    file of it that is not as RoboFollow wrote it."""


def read_run_object(path: Path, what: str) -> dict:
    """A file that holds one JSON object (`what` it is), read up to MAX_JSON_BYTES."""
    value, problem = read_json_object(path, MAX_JSON_BYTES)
    if problem:
        raise RunReadError(f"{path}: {problem} ({what} expected)")
    return value


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


def present(path: Path) -> bool:
    """Whether a file of the run is there: False where nothing is, True for a regular file (its
    links followed), EvalRunError for anything else (a FIFO, a device, a folder, a dangling
    link): a run's file that is not a file is never read, nor taken for an absent one."""
    if not os.path.lexists(path):
        return False
    problem = file_problem(path, sys.maxsize)
    if problem:
        raise EvalRunError(f"{path}: {problem}")
    return True


def _scan(path: Path) -> tuple[list[dict], list[bytes], list[tuple[int, bytes, str]]]:
    """The whole records of a results file, their lines, and its corrupt lines (number, line,
    what is wrong). Lines end at "\\n" only; a last line cut short by a kill is removed from
    the file. At most MAX_RESULTS_BYTES are read."""
    if not present(path):
        return [], [], []
    data, problem = read_file_at_most(path, MAX_RESULTS_BYTES)
    if problem:
        raise EvalRunError(f"{path}: {problem} (an episode's record takes about 2 KB; "
                           "a run this large is run in shards, eval --shard I/N)")
    whole = data[:data.rfind(b"\n") + 1]
    if len(whole) != len(data):
        with open(in_place(path.parent, path.name), "r+b") as f:
            f.truncate(len(whole))
    records, lines, corrupt, seen = [], [], [], {}
    for line in json_lines(whole):
        record = line.value
        why = line.problem or record_problem(record)
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
    side = in_place(path.parent, DROPPED)
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
            self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW
                              | os.O_NONBLOCK, 0o644)
        except OSError as error:
            raise EvalOutputError(f"cannot write {path}: {error.strerror or error}") from None
        info = os.fstat(self.fd)
        problem = not_regular(info.st_mode) or _linked_elsewhere(info)
        if problem:
            os.close(self.fd)
            raise EvalOutputError(f"cannot write {path}: {problem}")

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
    """Whether a folder holds files beyond the lock and a write a kill left unfinished."""
    return out.is_dir() and any(p.name != LOCK and not p.name.endswith(".partial")
                                for p in out.iterdir())


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
        if not present(out / RUN_FILE) and _holds_files(out):
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
        fd = os.open(in_place(out, LOCK), os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
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
    return (present(out / RUN_FILE)
            and (not present(results) or results.stat().st_size == 0)
            and not present(out / SUMMARY) and not present(out / SCORES))


def finished(out: Path) -> bool:
    """Whether the folder keeps a finished run's results: its summary and scores."""
    return present(out / SUMMARY) and present(out / SCORES)


def _lines(path: Path) -> int:
    """How many lines a file holds, read in blocks."""
    count = 0
    with open(path, "rb") as stream:
        while block := stream.read(1 << 20):
            count += block.count(b"\n")
    return count


def summarised_episodes(run: Path) -> int | None:
    """How many episodes the run's summary (RUN/summary.json) counts, if it has one (checked:
    a JSON object whose `episodes` is a whole number from 0)."""
    path = run / SUMMARY
    if not present(path):
        return None
    summary = read_run_object(path, "a run's summary")
    if "episodes" not in summary:
        raise RunReadError(f"{path}: no \"episodes\"")
    count = summary["episodes"]
    if isinstance(count, bool) or not isinstance(count, int) or count < 0:
        raise RunReadError(f"{path}: episodes is {shown(count)}, not a whole number from 0")
    return count


def check_whole(out: Path) -> None:
    """EvalRunError for a finished run whose results file holds fewer lines than its summary
    counts episodes (an emptied or replaced file): resuming it would run its episodes again
    over its scores. (Corrupt lines count: --drop-corrupt repairs those.)"""
    if not (finished(out) and present(out / RESULTS)):
        return
    kept, counted = _lines(out / RESULTS), summarised_episodes(out)
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
    if not present(run_file) or _unstarted(out):
        return
    previous = read_run_object(run_file, "a run's options")
    if not resume:
        raise EvalRunError(f"{out} already holds a run; pass --resume to continue it, or "
                           "choose another folder")
    if not present(out / RESULTS):
        raise EvalRunError(f"{out} holds a finished run that keeps only its scores "
                           f"({SCORES}, no {RESULTS}); it cannot be resumed or written over: "
                           "choose another folder")

    problem = changed_options(_named_release(previous), _named_release(options))
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
    if not present(run_file) or _unstarted(out):
        write_json(run_file, dict(options, provenance=[environment]))
        return
    if environment is None:  # (a resume that runs nothing adds no environment)
        return
    recorded = read_run_object(run_file, "a run's options")
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
    write_file(path, text.encode("utf-8"))


def write_file(path: Path, data: bytes) -> None:
    """A file written whole (atomically), or EvalOutputError saying why not."""
    try:
        write_bytes_atomic(path, data)
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


def in_place(out: Path, *parts: str) -> Path:
    """safe_path for a file written in place (appended to, cut short, locked), refused too
    where it is hard-linked elsewhere: its other names would change with it. (Files written
    whole are renamed into place, which leaves other names as they were.)"""
    path = safe_path(out, *parts)
    try:
        problem = _linked_elsewhere(os.lstat(path))
    except OSError:
        return path  # (not there yet)
    if problem:
        raise EvalOutputError(f"{path}: {problem}")
    return path


def _linked_elsewhere(info: os.stat_result) -> str | None:
    """Why a file the run would write in place is not its own: it is hard-linked elsewhere."""
    if stat.S_ISREG(info.st_mode) and info.st_nlink > 1:
        return (f"a file hard-linked elsewhere ({info.st_nlink} names); RoboFollow writes "
                "only files of its own: copy it, or choose another folder")
    return None


CONTROLS = "controls"  # RUN/controls/<instruction mode>: a run's control arms


def control_arms(run: Path) -> list[str]:
    """The modes of the run's control arms (RUN/controls/<mode> holding a run), sorted;
    EvalOutputError where RUN/controls or an arm is a symbolic link (a run's arms live
    inside it: nothing is read or written through a link)."""
    folder = safe_path(run, CONTROLS)
    if not folder.is_dir():
        return []
    return sorted(arm.name for arm in folder.iterdir()
                  if present(safe_path(run, CONTROLS, arm.name) / RUN_FILE))
