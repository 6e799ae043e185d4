"""`robofollow eval`: a policy over the compiled episodes, results appended per episode.

RUN/run.json        the options (a resumed run must use the same)
RUN/episodes.jsonl  one line per finished episode, appended as episodes finish (each line is
                    written whole; a line cut by a kill, or by a write that failed, is dropped,
                    so every finished episode is kept exactly once). A corrupt line (not a
                    whole record, or an episode already recorded) stops --resume with its
                    line number; --drop-corrupt moves such lines to episodes.jsonl.dropped
RUN/scores.csv.gz   every episode's id, hash, split digest, motion, IS, ES and completion
                    (eval/running/scores.py): what a later run is compared with, episode by episode
RUN/summary.json    the paper's Table 1 over every line: cells and avg (0-100), the chance and
                    followed-instruction references, L1 and L3 cells split by motion (moved /
                    as-trained; records written before they carried it take it from the
                    compiled episode), and the episodes that ended in a policy failure
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

import hashlib
import re
import sys
from collections import Counter
from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, replace
from functools import partial
from pathlib import Path

import numpy as np
from tqdm import tqdm

from robofollow.benchmark.episode import Benchmark, Episode
from robofollow.compiled_cache import Episodes
from robofollow.errors import RoboFollowError, UsageError, error_text
from robofollow.eval.policies.loading import load_policy
from robofollow.eval.policies.policy_kind import is_trained, policy_kind
from robofollow.eval.running.chance import references
from robofollow.eval.running.episode import EpisodeRun, run_episode
from robofollow.eval.running.instructions import given_instruction
from robofollow.eval.running.run_folder import (
    RESULTS,
    RESUMABLE,
    SCORES,
    SUMMARY,
    EvalOutputError,
    EvalRunError,
    ResultsFile,
    check_out,
    check_prepare,
    check_whole,
    drop_corrupt_lines,
    prepare,
    read_results,
    run_lock,
    safe_path,
    write_json,
)
from robofollow.eval.running.run_folder import finished as run_finished
from robofollow.eval.running.scores import write_scores
from robofollow.eval.statistics.metrics import table
from robofollow.provenance import environment
from robofollow.sim.cameras import side_by_side
from robofollow.sim.simulation import CONTROL_HZ
from robofollow.sim.stage import Stage
from robofollow.sim.video import captioned, write_video
from robofollow.trajectory import Trajectory
from robofollow.workers import WorkerStartError, results


class EvalPolicyError(EvalRunError):
    """The policy cannot be built."""


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
    shard: str | None = None  # "I/N": the I-th of N round-robin parts of the episodes
    controls: tuple[str, ...] = ()  # the control arms run after it (RUN/controls/<mode>)
    release: str | None = None  # the release its episodes come from, and its digest (None: a
    release_digest: str | None = None  # working compile, or a run made before releases)
    specs: str | None = None  # a working compile's specs (--specs), instead of a release

    def to_json(self) -> dict:
        data = dict(asdict(self), scenes=list(self.scenes), levels=list(self.levels),
                    tasks=list(self.tasks), controls=list(self.controls))
        for key, unset in (("shard", None), ("controls", []), ("release", None),
                           ("release_digest", None), ("specs", None)):
            if data[key] == unset:
                del data[key]  # (runs made before the option have no such key)
        return data

    def arm(self, mode: str) -> EvalOptions:
        """The options of its control arm with `mode` instructions."""
        return replace(self, instruction_mode=mode, controls=())


_SHARD = re.compile(r"([0-9]{1,9})/([0-9]{1,9})")


def shard_of(text: str, episodes: int | None = None) -> tuple[int, int]:
    """'I/N' -> (I, N), 1 <= I <= N (and N at most the run's `episodes`, where given: every
    shard holds at least one)."""
    found = _SHARD.fullmatch(text)
    index, count = (int(found[1]), int(found[2])) if found else (0, 0)
    if not 1 <= index <= count:
        raise UsageError(f"shard {text!r}: expected I/N with 1 <= I <= N, e.g. 1/4")
    if episodes is not None and count > episodes:
        raise UsageError(f"shard {text}: the run has {episodes} episode"
                         f"{'s' if episodes != 1 else ''}, so at most {episodes} shards")
    return index, count


def select_episodes(benchmark: Episodes, options: EvalOptions) -> list[Episode]:
    """The options' episodes, in the compiled order (only those are parsed); of a shard
    I/N, every N-th of them from the I-th."""

    def chosen_id(episode_id: str) -> bool:
        task, _, round_index = episode_id.partition("#r")
        scene, level, _ = task.split("/", 2)
        return (scene in options.scenes and level in options.levels
                and int(round_index) <= options.rounds
                and (not options.tasks or task in options.tasks))

    chosen = benchmark.episodes(chosen_id)
    if options.sample:
        kept = set()
        for tasks in _tasks_by_cell(chosen).values():
            step = len(tasks) / min(options.sample, len(tasks))
            kept.update(tasks[int(i * step)] for i in range(min(options.sample, len(tasks))))
        chosen = [e for e in chosen if e.task in kept]
    if options.shard:
        index, count = shard_of(options.shard, len(chosen))
        chosen = chosen[index - 1::count]
    return chosen


def _tasks_by_cell(episodes: list[Episode]) -> dict[tuple[str, str], list[str]]:
    """Each scene x level's task ids, in the compiled order."""
    cells: dict[tuple[str, str], list[str]] = {}
    for e in episodes:
        tasks = cells.setdefault((e.scene, e.level), [])
        if e.task not in tasks:
            tasks.append(e.task)
    return cells


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


START_TOLERANCE_M = 0.001  # realised initial states this close count as one start (compare)


def start_hash(positions: np.ndarray, quaternions: np.ndarray) -> str:
    """The realised initial state on a grid: positions to START_TOLERANCE_M, orientations to
    1e-3 (each quaternion's sign fixed). Two runs of an episode on other machines share it
    when their starts agree within the tolerance (bar a value on a grid boundary); starts
    further apart always differ."""
    signs = np.where(quaternions[:, :1] < 0, -1.0, 1.0)
    grid = np.concatenate([np.round(positions / START_TOLERANCE_M).ravel(),
                           np.round(quaternions * signs / 1e-3).ravel()]).astype(np.int64)
    return _digest(grid.tobytes())


def trajectory_hash(trajectory: Trajectory) -> str:
    """The recorded episode bit for bit: joint states, actions, body positions and
    orientations at every frame (a rerun reproduces it exactly on the same build)."""
    arrays = (trajectory.state, trajectory.action, trajectory.positions, trajectory.quaternions)
    return _digest(b"".join(np.ascontiguousarray(a, np.float64).tobytes() for a in arrays))


def result_record(episode: Episode, instruction: str, run: EpisodeRun) -> dict:
    """An episode's line in RUN/episodes.jsonl. `instruction` is the one given; where it is
    not the task's own (the empty and shuffled controls), `task_instruction` holds that."""
    score, trajectory = run.score, run.trajectory
    start = trajectory.positions[0].tobytes() + trajectory.quaternions[0].tobytes()
    own = {} if instruction == episode.instruction else {
        "task_instruction": episode.instruction}
    return {
        "episode": episode.id, "scene": episode.scene, "level": episode.level,
        "task": episode.task, "layout": episode.layout, "round": episode.round,
        "motion": episode.motion, "seed": episode.seed, "instruction": instruction, **own,
        "intent_score": score.intent_score, "execution_score": score.execution_score,
        "complete": score.complete, "other_branch": score.other_branch,
        "stages": [s.model_dump(mode="json") for s in score.stages],
        "executed_behaviour": (score.executed_behaviour.model_dump(mode="json")
                               if score.executed_behaviour else None),
        "steps": run.steps, "queries": run.queries, "clipped": run.clipped, "error": run.error,
        "seconds": round(run.seconds, 3), "observed": sorted(run.uses),
        "hashes": {"episode": episode.hash, "split": episode.split,
                   "instruction": _digest(instruction.encode()),
                   "initial_state": _digest(start),
                   "start": start_hash(trajectory.positions[0], trajectory.quaternions[0]),
                   "trajectory": trajectory_hash(trajectory)},
        "start_tolerance_m": START_TOLERANCE_M}


def episode_record(compiled: Benchmark, episode: Episode, instruction: str,
                   run: EpisodeRun) -> dict:
    """The episode's full record: `result_record` with its chance and followed references."""
    return dict(result_record(episode, instruction, run),
                **references(compiled, episode, instruction))


class Evaluator:
    """Evaluates episodes one after another (one per worker process)."""

    def __init__(self, compiled: Benchmark, options: EvalOptions, out: Path):
        self.compiled, self.options, self.out = compiled, options, out
        self.policy = build_policy(options.policy)
        self.stage = Stage()

    def __call__(self, episode: Episode) -> dict:
        instruction = given_instruction(self.compiled, episode, self.options.instruction_mode)
        frames: list = []
        on_frame = ((lambda stage: frames.append(captioned(
            side_by_side(stage.cameras.images()), instruction, len(frames))))
                    if self.options.video != "none" else None)
        run = run_episode(self.compiled, self.stage, episode, self.policy, instruction,
                          on_frame=on_frame, timeout=self.options.policy_timeout)
        record = episode_record(self.compiled, episode, instruction, run)
        if frames and (self.options.video == "all" or not run.score.complete):
            name = episode.id.replace("/", "__").replace("#", "_") + ".mp4"
            path = safe_path(self.out, "videos", name)
            try:
                path.parent.mkdir(exist_ok=True)
                write_video(path, frames, CONTROL_HZ)
            except OSError as error:
                raise EvalOutputError(f"cannot write the video {path}: "
                                      f"{error.strerror or error}{RESUMABLE}") from None
            record["video"] = f"videos/{name}"
        return record

    def close(self) -> None:
        self.stage.close()


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
                              f"{error_text(error)}") from None


class _LostEpisodes:
    """Records, in this process, the episodes whose policy process died: each is scored as it
    stands at its start, with the reason as its policy failure."""

    def __init__(self, compiled: Benchmark, options: EvalOptions):
        self.compiled, self.options = compiled, options
        self.stage: Stage | None = None

    def __call__(self, episode: Episode, what: str) -> dict:
        self.stage = self.stage or Stage()
        instruction = given_instruction(self.compiled, episode, self.options.instruction_mode)
        run = run_episode(self.compiled, self.stage, episode, None, instruction,
                          failed=f"the policy process {what} during the episode")
        return episode_record(self.compiled, episode, instruction, run)

    def close(self) -> None:
        if self.stage is not None:
            self.stage.close()


def _isolated(spec: str) -> bool:
    """Whether a policy is someone else's code (module:factory), run in a worker process
    even with one worker; reference policies, servers and checkpoints run in this one."""
    return policy_kind(spec) == "factory"


# -- RUN/episodes.jsonl ------------------------------------------------------------------------

def _failure_reason(error: str) -> str:
    return re.sub(r"^(step \d+|reset): ", "", error)


def with_motion(results: list[dict], motions: Mapping[str, str | None]) -> list[dict]:
    """The records, each with its task's motion (moved / as-trained, None at L0 and L2): its
    own, else its compiled episode's (`motions`, by episode id) for records written before
    they carried it; a record with neither is left as it is (its motion unknown)."""
    return [record if "motion" in record or record["episode"] not in motions
            else dict(record, motion=motions[record["episode"]]) for record in results]


def summary(results: list[dict], options: EvalOptions) -> dict:
    ordered = sorted(results, key=lambda r: r["episode"])  # same sums in any finishing order
    reasons = Counter(_failure_reason(r["error"]) for r in ordered if r.get("error"))
    splits: dict[str, set] = {}
    for record in ordered:
        splits.setdefault(record["scene"], set()).add(record.get("hashes", {}).get("split"))
    observed = sorted({part for record in ordered for part in record.get("observed", ())})
    return {"policy": options.policy, "instruction_mode": options.instruction_mode,
            "episodes": len(results),
            # what the policy read (records that say); "objects" without "images": the
            # objects observation stood in for perception (perception removed)
            "observed": observed,
            "splits": {scene: sorted(d for d in digests if d) for scene, digests in
                       splits.items()},  # each scene's split digest (records that carry one)
            **table(ordered),
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


def episode_records(compiled: Episodes, options: EvalOptions, out: Path,
                    episodes: list[Episode], workers: int = 1, executor: str = "process",
                    isolate: bool | None = None) -> Iterator[dict]:
    """Each episode's record, in the order they finish (`out`: where videos go); `isolate`:
    run the policy in worker processes even with one worker (default: for policies that are
    not RoboFollow's own)."""
    isolate = _isolated(options.policy) if isolate is None else isolate
    lost = _LostEpisodes(compiled, options)
    make = partial(Evaluator, compiled, options, out)
    try:
        yield from results(make, episodes, workers, executor, lost, isolate)
    except WorkerStartError as error:
        if error.reported:
            raise
        raise EvalPolicyError(f"--policy {options.policy!r}: {error}") from None
    finally:
        lost.close()


def evaluate(compiled: Episodes, out: Path, options: EvalOptions, workers: int = 1,
             resume: bool = False, progress: bool = True, executor: str = "process",
             drop_corrupt: bool = False, isolate: bool | None = None,
             up_to_round: int | None = None) -> dict:
    """Run (or finish) the evaluation; returns the summary (also written to summary.json).
    `drop_corrupt`: move corrupt lines of a resumed run aside (else they stop it);
    `isolate`: run the policy in worker processes even with one worker (default: for
    policies that are not RoboFollow's own); `up_to_round`: run only the rounds up to this
    one for now (a sequential comparison adds rounds one at a time)."""
    if (options.spec_digest, options.release) != (compiled.spec.digest, compiled.release):
        raise EvalRunError("the options' spec digest or release is not the benchmark's")
    check_out(out)
    with run_lock(out):
        check_prepare(out, options.to_json(), resume)
        check_whole(out)
        episodes = [e for e in select_episodes(compiled, options)
                    if up_to_round is None or e.round <= up_to_round]
        results_path = safe_path(out, RESULTS)
        finished = (drop_corrupt_lines if drop_corrupt else read_results)(results_path)
        done = {r["episode"] for r in finished}
        todo = [e for e in episodes if e.id not in done]
        prepare(out, options.to_json(), resume,  # (what runs nothing adds no environment)
                environment(is_trained(options.policy)) if todo else None)
        if not todo and run_finished(out):  # a finished run is read, never written again
            print(f"{out}: every episode is already recorded; nothing to run", file=sys.stderr)
            return summary(with_motion(finished, {e.id: e.motion for e in episodes}), options)
        bar = tqdm(total=len(episodes), initial=len(episodes) - len(todo), desc="evaluating",
                   unit="episode", disable=not progress, smoothing=0.1)
        with bar, ResultsFile(results_path) as sink:
            for record in episode_records(compiled, options, out, todo, workers, executor,
                                          isolate):
                sink.append(record)  # one whole line, or none
                finished.append(record)
                bar.update()
        finished = with_motion(finished, {e.id: e.motion for e in episodes})
        result = summary(finished, options)
        write_json(safe_path(out, SUMMARY), result)
        write_scores(safe_path(out, SCORES), finished)
    return result
