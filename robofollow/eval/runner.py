"""`robofollow eval`: a policy over the compiled episodes, results appended per episode.

RUN/run.json        the options (a resumed run must use the same)
RUN/episodes.jsonl  one line per finished episode, appended as episodes finish (each line is
                    written whole; a line cut by a kill, or by a write that failed, is dropped,
                    so every finished episode is kept exactly once). A corrupt line (not a
                    whole record, or an episode already recorded) stops --resume with its
                    line number; --drop-corrupt moves such lines to episodes.jsonl.dropped
RUN/summary.json    the paper's Table 1 over every line: cells and avg (0-100), the chance and
                    followed-instruction references, and the episodes that ended in a policy
                    failure
RUN/videos/         mp4s of failed (or all) episodes, with --video
RUN/.lock           held (flock) while a run uses the folder: a second run on it stops at once;
                    the lock of a killed run goes with its process

Every output path is checked before any episode runs, and a write that fails mid-run (a full
disk) stops the run with a message, leaving a resumable folder. An in-process policy that is
not RoboFollow's own (module:factory) runs in a supervised worker process even with one
worker, so that its process dying costs its episode (recorded as a policy failure with the
reason), not the run.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import os
import re
import sys
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path

from tqdm import tqdm

from robofollow.build import Compiled, all_episodes
from robofollow.data.files import changed_options, json_line, write_json_atomic
from robofollow.errors import RoboFollowError
from robofollow.eval.chance import references
from robofollow.eval.episode import EpisodeRun, run_episode
from robofollow.eval.instructions import given_instruction
from robofollow.eval.loading import is_server, load_policy
from robofollow.eval.reference import REFERENCE_POLICIES
from robofollow.oracle.metrics import table
from robofollow.sim.cameras import side_by_side
from robofollow.sim.simulation import CONTROL_HZ
from robofollow.sim.stage import Stage
from robofollow.sim.video import write_video
from robofollow.workers import WorkerStartError, results

RUN_FILE, RESULTS, SUMMARY, LOCK = "run.json", "episodes.jsonl", "summary.json", ".lock"
DROPPED = RESULTS + ".dropped"  # corrupt lines that --drop-corrupt moved out of RESULTS
VIDEO_MODES = ("none", "failures", "all")
_RECORD_FIELDS = {"episode": str, "scene": str, "level": str, "task": str,
                  "intent_score": (int, float), "execution_score": (int, float),
                  "complete": bool}  # what the summary reads of every record


class EvalRunError(RoboFollowError):
    """The run folder cannot be used as asked (or the run cannot go on)."""


class EvalOutputError(EvalRunError):
    """An output path that cannot be written."""


class EvalPolicyError(EvalRunError):
    """The policy cannot be built."""


class RunInUseError(EvalRunError):
    """Another run holds the run folder."""


class CorruptResultsError(EvalRunError):
    """Lines of RUN/episodes.jsonl that are not whole episode records."""

    def __init__(self, path: Path, problems: list[tuple[int, str]]):
        shown = "; ".join(f"line {number}: {why}" for number, why in problems[:5])
        more = f" (and {len(problems) - 5} more)" if len(problems) > 5 else ""
        count = f"{len(problems)} corrupt line{'s' if len(problems) != 1 else ''}"
        super().__init__(
            f"{path} has {count}: {shown}{more}. To resume, run the same command with "
            f"--resume --drop-corrupt: it moves such lines to {path.with_name(DROPPED)} and "
            "evaluates again the episodes left without a record")
        self.path, self.problems = path, problems


@dataclass(frozen=True)
class EvalOptions:
    policy: str
    scenes: tuple[str, ...]
    levels: tuple[str, ...]
    rounds: int
    instruction_mode: str
    video: str
    spec_digest: str
    tasks: tuple[str, ...] = ()  # task ids (scene/level/label) to keep; empty: every task
    sample: int | None = None  # keep this many tasks per scene and level, evenly spread
    policy_timeout: float | None = None  # seconds an in-process policy call may take

    def to_json(self) -> dict:
        return dict(asdict(self), scenes=list(self.scenes), levels=list(self.levels),
                    tasks=list(self.tasks))


def select_episodes(compiled: Compiled, options: EvalOptions) -> list[dict]:
    chosen = [e for e in all_episodes(compiled) if e["scene"] in options.scenes
              and e["level"] in options.levels and e["round"] <= options.rounds
              and (not options.tasks or e["task"] in options.tasks)]
    if options.sample:
        kept = set()
        for tasks in _tasks_by_cell(chosen).values():
            step = len(tasks) / min(options.sample, len(tasks))
            kept.update(tasks[int(i * step)] for i in range(min(options.sample, len(tasks))))
        chosen = [e for e in chosen if e["task"] in kept]
    return chosen


def _tasks_by_cell(episodes: list[dict]) -> dict[tuple[str, str], list[str]]:
    """Each scene x level's task ids, in the compiled order."""
    cells: dict[tuple[str, str], list[str]] = {}
    for e in episodes:
        tasks = cells.setdefault((e["scene"], e["level"]), [])
        if e["task"] not in tasks:
            tasks.append(e["task"])
    return cells


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def result_record(episode: dict, instruction: str, run: EpisodeRun) -> dict:
    score, trajectory = run.score, run.trajectory
    start = trajectory.positions[0].tobytes() + trajectory.quaternions[0].tobytes()
    return {
        "episode": episode["episode"], "scene": episode["scene"], "level": episode["level"],
        "task": episode["task"], "layout": episode["layout"], "round": episode["round"],
        "seed": episode["seed"], "instruction": instruction,
        "intent_score": score.intent_score, "execution_score": score.execution_score,
        "complete": score.complete, "other_branch": score.other_branch,
        "stages": [s.model_dump(mode="json") for s in score.stages],
        "executed_behaviour": (score.executed_behaviour.model_dump(mode="json")
                               if score.executed_behaviour else None),
        "steps": run.steps, "queries": run.queries, "clipped": run.clipped, "error": run.error,
        "seconds": round(run.seconds, 3),
        "hashes": {"episode": episode["hash"], "instruction": _digest(instruction.encode()),
                   "initial_state": _digest(start)}}


class Evaluator:
    """Evaluates episodes one after another (one per worker process)."""

    def __init__(self, compiled: Compiled, options: EvalOptions, out: Path):
        self.compiled, self.options, self.out = compiled, options, out
        self.policy = build_policy(options.policy)
        self.stage = Stage()

    def __call__(self, episode: dict) -> dict:
        instruction = given_instruction(self.compiled, episode, self.options.instruction_mode)
        frames: list = []
        on_frame = ((lambda stage: frames.append(side_by_side(stage.cameras.images())))
                    if self.options.video != "none" else None)
        run = run_episode(self.compiled, self.stage, episode, self.policy, instruction,
                          on_frame=on_frame, timeout=self.options.policy_timeout)
        record = dict(result_record(episode, instruction, run),
                      **references(self.compiled, episode, instruction))
        if frames and (self.options.video == "all" or not run.score.complete):
            name = episode["episode"].replace("/", "__").replace("#", "_") + ".mp4"
            path = self.out / "videos" / name
            try:
                path.parent.mkdir(exist_ok=True)
                write_video(path, frames, CONTROL_HZ)
            except OSError as error:
                raise EvalOutputError(f"cannot write the video {path}: "
                                      f"{error.strerror or error}{_RESUMABLE}") from None
            record["video"] = f"videos/{name}"
        return record

    def close(self) -> None:
        self.stage.close()


def _text(error: BaseException) -> str:
    text = str(error)
    return f"{type(error).__name__}: {text}" if text else repr(error)


def build_policy(spec: str):
    """The --policy's policy, or EvalPolicyError naming it and saying what went wrong (a
    factory that raises or exits included)."""
    try:
        return load_policy(spec)
    except KeyboardInterrupt:
        raise
    except EvalPolicyError:
        raise
    except RoboFollowError as error:  # (PolicyLoadError names the policy)
        raise EvalPolicyError(error.render()) from None
    except BaseException as error:  # noqa: B036 (a factory's bug, SystemExit included)
        raise EvalPolicyError(f"--policy {spec!r}: the policy could not be built: "
                              f"{_text(error)}") from None


class _LostEpisodes:
    """Records, in this process, the episodes whose policy process died: each is scored as it
    stands at its start, with the reason as its policy failure."""

    def __init__(self, compiled: Compiled, options: EvalOptions):
        self.compiled, self.options = compiled, options
        self.stage: Stage | None = None

    def __call__(self, episode: dict, what: str) -> dict:
        self.stage = self.stage or Stage()
        instruction = given_instruction(self.compiled, episode, self.options.instruction_mode)
        run = run_episode(self.compiled, self.stage, episode, None, instruction,
                          failed=f"the policy process {what} during the episode")
        return dict(result_record(episode, instruction, run),
                    **references(self.compiled, episode, instruction))

    def close(self) -> None:
        if self.stage is not None:
            self.stage.close()


def _isolated(spec: str) -> bool:
    """Whether a policy is someone else's code (module:factory), run in a worker process
    even with one worker; reference policies, servers and checkpoints run in this one."""
    return not (spec in REFERENCE_POLICIES or is_server(spec) or spec.startswith("baseline:")
                or Path(spec).is_dir())


# -- RUN/episodes.jsonl ------------------------------------------------------------------------

_RESUMABLE = ("; the finished episodes are kept: fix it and run the same command with --resume "
              "to continue")


def _record_problem(record) -> str | None:
    if not isinstance(record, dict):
        return f"a JSON {type(record).__name__}, not an episode record"
    for key, kind in _RECORD_FIELDS.items():
        if key not in record:
            return f"no {key!r}"
        if not isinstance(record[key], kind) or (kind != bool and isinstance(record[key], bool)):
            return f"{key!r} is {json.dumps(record[key])[:40]}"
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
    for number, line in enumerate(whole.split(b"\n")[:-1], start=1):
        if not line.strip():
            continue
        why = None
        try:
            record = json.loads(line.decode("utf-8"))
        except UnicodeDecodeError as error:
            why = f"not UTF-8 text (byte {error.start + 1})"
        except json.JSONDecodeError as error:
            why = f"not JSON ({error.msg} at column {error.colno})"
        else:
            why = _record_problem(record)
            if why is None and record["episode"] in seen:
                why = f"repeats episode {record['episode']} of line {seen[record['episode']]}"
        if why is not None:
            corrupt.append((number, line, why))
            continue
        seen[record["episode"]] = number
        records.append(record)
        lines.append(line)
    return records, lines, corrupt


def read_results(path: Path) -> list[dict]:
    """The finished episodes; a last line cut short by a kill is removed from the file, and a
    corrupt line raises CorruptResultsError (with its line number and what is wrong)."""
    records, _, corrupt = _scan(path)
    if corrupt:
        raise CorruptResultsError(path, [(number, why) for number, _, why in corrupt])
    return records


def _drop_corrupt(path: Path) -> list[dict]:
    """Move the corrupt lines of a results file to its side file (appended, nothing is
    lost), keep the whole records; returns them."""
    records, lines, corrupt = _scan(path)
    if not corrupt:
        return records
    side, partial_file = path.with_name(DROPPED), path.with_name(path.name + ".partial")
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
            self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
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
                                  f"{_RESUMABLE}") from None

    def close(self) -> None:
        os.close(self.fd)

    def __enter__(self) -> "ResultsFile":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _failure_reason(error: str) -> str:
    return re.sub(r"^(step \d+|reset): ", "", error)


def summary(results: list[dict], options: EvalOptions) -> dict:
    ordered = sorted(results, key=lambda r: r["episode"])  # same sums in any finishing order
    reasons = Counter(_failure_reason(r["error"]) for r in ordered if r.get("error"))
    return {"policy": options.policy, "instruction_mode": options.instruction_mode,
            "episodes": len(results), **table(ordered),
            "policy_failures": {"episodes": sum(reasons.values()),
                                "reasons": dict(reasons.most_common(5))}}


def failures_text(result: dict) -> str | None:
    """The summary's line on the episodes that ended in a policy failure, if any did."""
    failures = result.get("policy_failures", {})
    count = failures.get("episodes", 0)
    if not count:
        return None
    lines = [f"{count} of {result['episodes']} episode{'s' if result['episodes'] != 1 else ''}"
             f" ended in a policy failure (scored as they stood; every reason is in "
             f"episodes.jsonl and the report):"]
    lines += [f"  {n} x {reason}" for reason, n in failures.get("reasons", {}).items()]
    return "\n".join(lines)


# -- the run folder ----------------------------------------------------------------------------

def _holds_files(out: Path) -> bool:
    return out.is_dir() and any(p.name != LOCK for p in out.iterdir())


def _check_out(out: Path) -> None:
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
        fd = os.open(out / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
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


def _write_json(path: Path, data) -> None:
    try:
        write_json_atomic(path, data)
    except OSError as error:
        raise EvalOutputError(f"cannot write {path}: {error.strerror or error}"
                              f"{_RESUMABLE}") from None


def _prepare(out: Path, options: EvalOptions, resume: bool) -> None:
    run_file = out / RUN_FILE
    if run_file.is_file():
        try:
            previous = json.loads(run_file.read_text(encoding="utf-8"))
        except (OSError, ValueError) as error:
            raise EvalRunError(f"{run_file} cannot be read: {error}") from None
        if not resume:
            raise EvalRunError(f"{out} already holds a run; pass --resume to continue it, or "
                               "choose another folder")
        problem = changed_options(previous, options.to_json())
        if problem:
            raise EvalRunError(f"{out} {problem}")
        return
    if _holds_files(out):
        raise EvalRunError(f"{out} is not empty and holds no run")
    _write_json(run_file, options.to_json())


def evaluate(compiled: Compiled, out: Path, options: EvalOptions, workers: int = 1,
             resume: bool = False, progress: bool = True, executor: str = "process",
             drop_corrupt: bool = False, isolate: bool | None = None) -> dict:
    """Run (or finish) the evaluation; returns the summary (also written to summary.json).
    `drop_corrupt`: move corrupt lines of a resumed run aside (else they stop it);
    `isolate`: run the policy in worker processes even with one worker (default: for
    policies that are not RoboFollow's own)."""
    if options.spec_digest != compiled.spec.digest:
        raise EvalRunError("the options' spec digest is not the compiled specs' digest")
    _check_out(out)
    with run_lock(out):
        _prepare(out, options, resume)
        episodes = select_episodes(compiled, options)
        results_path = out / RESULTS
        finished = (_drop_corrupt if drop_corrupt else read_results)(results_path)
        done = {r["episode"] for r in finished}
        todo = [e for e in episodes if e["episode"] not in done]
        isolate = _isolated(options.policy) if isolate is None else isolate
        lost = _LostEpisodes(compiled, options)
        bar = tqdm(total=len(episodes), initial=len(episodes) - len(todo), desc="evaluating",
                   unit="episode", disable=not progress, smoothing=0.1)
        with bar, ResultsFile(results_path) as sink:
            make = partial(Evaluator, compiled, options, out)
            try:
                for record in results(make, todo, workers, executor, lost, isolate):
                    sink.append(record)  # one whole line, or none
                    finished.append(record)
                    bar.update()
            except WorkerStartError as error:
                if error.reported:
                    raise
                raise EvalPolicyError(f"--policy {options.policy!r}: {error}") from None
            finally:
                lost.close()
        result = summary(finished, options)
        _write_json(out / SUMMARY, result)
    return result
