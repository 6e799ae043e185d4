"""Dataset generation throughput: `generate` (LeRobot v2.1, three 320x240 cameras) with 1 and
2 workers, against bare MuJoCo physics + rendering of the same frames.

    python bench/generate_bench.py [--runs 3] [--tasks 8] [--episodes-per-task 2]
                                   [--format lerobot-v2.1] [--projection-tasks N]
                                   [--json out.json]

Reports, as medians over runs (each run a fresh process and a fresh output folder):
  - demonstrations (episodes) per minute and frames per second, 1 and 2 workers;
  - the ratio of generation (1 worker) to bare cost: the same frames' physics steps and three
    camera renders with a plain mujoco.Renderer, nothing else (planning, settling, scoring,
    encoding, statistics and writing are all generation overhead);
  - peak resident memory per worker (for one worker, the process that records and writes);
  - the projected wall time of the full set (every training task x 50) with 2 workers, from
    the mean demonstration length over all training tasks (or --projection-tasks of them; one
    expert run each, no rendering) and the measured 2-worker frame rate (target <= 2 h).

The tasks are the current release's, as `robofollow generate` reads them.
"""

from __future__ import annotations

import robofollow  # noqa: F401  (first: it sets MUJOCO_GL before mujoco loads)

# isort: split
import argparse
import dataclasses
import json
import multiprocessing
import resource
import statistics
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
import pyarrow.parquet as pq

from robofollow import release
from robofollow.cli.common import positive
from robofollow.data.generate import generate
from robofollow.data.jobs import FORMATS, demo_jobs, select_tasks
from robofollow.data.units import Options
from robofollow.sim.cameras import CAMERA_NAMES
from robofollow.sim.rollout import ExpertRunner
from robofollow.sim.simulation import Simulation

FULL_PER_TASK = 50


def _labels(count: int) -> list[str]:
    """`count` training task labels, spread over the current release's."""
    labels = select_tasks(release.benchmark(), None)
    return labels[::max(1, len(labels) // count)][:count]


def _generate_child(out: str, options: Options, workers: int, queue) -> None:
    compiled = release.benchmark()  # the current release, as `robofollow generate` reads it
    began = time.perf_counter()
    result = generate(compiled, Path(out), options, workers, progress=False)
    seconds = time.perf_counter() - began
    manifest = json.loads((Path(out) / "manifest.json").read_text())
    frames = sum(d["length"] for d in manifest["demos"])
    peak = {"self": resource.RUSAGE_SELF, "workers": resource.RUSAGE_CHILDREN}
    queue.put({"seconds": seconds, "episodes": result.episodes, "frames": frames,
               **{f"peak_mb_{k}": resource.getrusage(v).ru_maxrss / 1024
                  for k, v in peak.items()}})


def timed_generation(options: Options, workers: int, keep: Path | None = None) -> dict:
    context = multiprocessing.get_context("spawn")
    with tempfile.TemporaryDirectory() as folder:
        out = keep or Path(folder) / "demos"
        queue = context.Queue()
        process = context.Process(target=_generate_child, args=(str(out), options, workers,
                                                                queue))
        process.start()
        result = queue.get()
        process.join()
    return result


def bare_seconds(dataset: Path, width: int, height: int) -> float:
    """Physics steps and three renders per frame of the dataset's demonstrations."""
    compiled = release.benchmark()
    manifest = json.loads((dataset / "manifest.json").read_text())
    total = 0.0
    for demo in manifest["demos"]:
        task = next(t for t in compiled.spec.tasks if t.label == demo["label"])
        table = pq.read_table(dataset / f"data/chunk-000/episode_{demo['episodes'][0]:06d}"
                                        ".parquet")
        actions = np.array(table.column("action").to_pylist(), dtype=np.float64)
        sim = Simulation(compiled.spec.scenes[task.scene], task.layout, width, height)
        sim.reset(demo["seed"])
        renderer = mujoco.Renderer(sim.model, height, width)
        began = time.perf_counter()
        for camera in CAMERA_NAMES:  # frame 0
            renderer.update_scene(sim.data, camera)
            renderer.render()
        for action in actions[:-1]:
            sim.step(action)
            for camera in CAMERA_NAMES:
                renderer.update_scene(sim.data, camera)
                renderer.render()
        total += time.perf_counter() - began
        renderer.close()
    return total


def mean_length(labels: list[str]) -> float:
    """Mean dataset frames per demonstration over these training tasks (episode 0 each)."""
    compiled = release.benchmark()
    lengths = []
    with ExpertRunner() as runner:
        for job in demo_jobs(compiled, 1, labels):
            run = runner.run(compiled, job.episode(0))
            lengths.append(run.steps)
    return float(np.mean(lengths))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=positive, default=3)
    parser.add_argument("--tasks", type=positive, default=8, help="training tasks sampled")
    parser.add_argument("--episodes-per-task", type=positive, default=2)
    parser.add_argument("--format", choices=FORMATS, default="lerobot-v2.1")
    parser.add_argument("--projection-tasks", type=positive, metavar="N",
                        help="training tasks whose mean demonstration length gives the "
                             "projection (default: every one)")
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args(argv)
    compiled = release.benchmark()
    labels = _labels(args.tasks)
    options = Options(args.format, args.episodes_per_task, tuple(labels), 320, 240, "sample",
                      compiled.spec.digest)
    print(f"{len(labels)} tasks x {args.episodes_per_task} demonstrations, {args.format}, "
          f"3 cameras at 320x240, {args.runs} runs per setting")
    figures: dict = {"tasks": labels, "episodes_per_task": args.episodes_per_task}
    for workers in (1, 2):
        runs = [timed_generation(options, workers) for _ in range(args.runs)]
        seconds = statistics.median(r["seconds"] for r in runs)
        frames, episodes = runs[0]["frames"], runs[0]["episodes"]
        figures[f"workers_{workers}"] = {
            "seconds": seconds, "episodes_per_min": episodes / seconds * 60,
            "frames_per_s": frames / seconds,
            # one worker records in the generating process itself; two are child processes
            "peak_mb_per_worker": max(r["peak_mb_self" if workers == 1 else "peak_mb_workers"]
                                      for r in runs), "frames": frames}
        print(f"{workers} worker(s): {episodes / seconds * 60:6.1f} episodes/min, "
              f"{frames / seconds:6.1f} frames/s ({seconds:.1f} s median for {episodes} "
              f"episodes, {frames} frames), peak memory per worker "
              f"{figures[f'workers_{workers}']['peak_mb_per_worker']:.0f} MB")
    with tempfile.TemporaryDirectory() as folder:
        kept = Path(folder) / "demos"  # the same frames, in the format bare_seconds reads
        timed_generation(dataclasses.replace(options, format="lerobot-v2.1"), 1, kept)
        bare = [bare_seconds(kept, 320, 240) for _ in range(args.runs)]
    bare_median = statistics.median(bare)
    ratio = figures["workers_1"]["seconds"] / bare_median
    figures["bare_seconds"], figures["ratio_to_bare"] = bare_median, ratio
    print(f"bare physics + 3 renders of the same frames: {bare_median:.1f} s -> generation "
          f"costs {ratio:.2f}x bare")
    length = mean_length(_labels(args.projection_tasks or len(compiled.spec.tasks)))
    full_frames = length * FULL_PER_TASK * len(compiled.spec.tasks)
    projected = full_frames / figures["workers_2"]["frames_per_s"]
    figures["mean_length"], figures["projected_full_hours"] = length, projected / 3600
    print(f"full set: {FULL_PER_TASK * len(compiled.spec.tasks)} episodes x {length:.0f} "
          f"frames mean -> projected {projected / 3600:.2f} h with 2 workers (target <= 2 h)")
    if args.json:
        Path(args.json).write_text(json.dumps(figures, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
