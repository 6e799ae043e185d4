"""`robofollow eval`: a policy over the compiled episodes, results appended per episode.

RUN/run.json        the options (a resumed run must use the same)
RUN/episodes.jsonl  one line per finished episode, appended as episodes finish (each line is
                    written whole; a line cut by a kill is dropped on resume, so every
                    finished episode is kept exactly once)
RUN/summary.json    the paper's Table 1 over every line: cells and avg (0-100), and the
                    chance and followed-instruction references
RUN/videos/         mp4s of failed (or all) episodes, with --video
"""

from __future__ import annotations

import hashlib
import json
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
from robofollow.eval.loading import load_policy
from robofollow.oracle.metrics import table
from robofollow.sim.cameras import side_by_side
from robofollow.sim.simulation import CONTROL_HZ
from robofollow.sim.stage import Stage
from robofollow.sim.video import write_video
from robofollow.workers import results

RUN_FILE, RESULTS, SUMMARY = "run.json", "episodes.jsonl", "summary.json"
VIDEO_MODES = ("none", "failures", "all")


class EvalRunError(RoboFollowError):
    """The run folder cannot be used as asked."""


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
        self.policy = load_policy(options.policy)
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
            (self.out / "videos").mkdir(exist_ok=True)
            write_video(self.out / "videos" / name, frames, CONTROL_HZ)
            record["video"] = f"videos/{name}"
        return record

    def close(self) -> None:
        self.stage.close()


def read_results(path: Path) -> list[dict]:
    """The finished episodes; a last line cut short by a kill is removed from the file."""
    if not path.is_file():
        return []
    data = path.read_bytes()
    whole = data[:data.rfind(b"\n") + 1]
    if len(whole) != len(data):
        with open(path, "r+b") as f:
            f.truncate(len(whole))
    return [json.loads(line) for line in whole.decode("utf-8").split("\n") if line.strip()]


def summary(results: list[dict], options: EvalOptions) -> dict:
    ordered = sorted(results, key=lambda r: r["episode"])  # same sums in any finishing order
    return {"policy": options.policy, "instruction_mode": options.instruction_mode,
            "episodes": len(results), **table(ordered)}


def _prepare(out: Path, options: EvalOptions, resume: bool) -> None:
    run_file = out / RUN_FILE
    if run_file.is_file():
        previous = json.loads(run_file.read_text(encoding="utf-8"))
        if not resume:
            raise EvalRunError(f"{out} already holds a run; pass --resume to continue it, or "
                               "choose another folder")
        problem = changed_options(previous, options.to_json())
        if problem:
            raise EvalRunError(f"{out} {problem}")
        return
    if out.is_dir() and any(out.iterdir()):
        raise EvalRunError(f"{out} is not empty and holds no run")
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(run_file, options.to_json())


def evaluate(compiled: Compiled, out: Path, options: EvalOptions, workers: int = 1,
             resume: bool = False, progress: bool = True, executor: str = "process") -> dict:
    """Run (or finish) the evaluation; returns the summary (also written to summary.json)."""
    if options.spec_digest != compiled.spec.digest:
        raise EvalRunError("the options' spec digest is not the compiled specs' digest")
    _prepare(out, options, resume)
    episodes = select_episodes(compiled, options)
    results_path = out / RESULTS
    finished = read_results(results_path)
    done = {r["episode"] for r in finished}
    todo = [e for e in episodes if e["episode"] not in done]
    bar = tqdm(total=len(episodes), initial=len(episodes) - len(todo), desc="evaluating",
               unit="episode", disable=not progress, smoothing=0.1)
    with bar, open(results_path, "a", encoding="utf-8") as sink:
        make = partial(Evaluator, compiled, options, out)
        for record in results(make, todo, workers, executor):
            sink.write(json_line(record))  # one whole line
            sink.flush()
            finished.append(record)
            bar.update()
    result = summary(finished, options)
    write_json_atomic(out / SUMMARY, result)
    return result
