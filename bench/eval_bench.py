"""Evaluation throughput: `robofollow eval`'s runner with the expert policy, 1 and 2 workers.

    python bench/eval_bench.py [--runs 3] [--episodes 16] [--expert-episodes 64]
                               [--policies expert,seeing] [--json out.json]

Two policies over sampled episodes of the current release (spread over the tasks of all
scenes, L0, round 1; the image-free expert gets a larger sample, so that pool start-up does not
dominate), with the options `robofollow eval` gives the runner, medians over runs in fresh
processes:
  - `expert` (privileged, no images): episodes per minute;
  - `seeing` (the expert, but it asks for all three 320x240 camera images and one action per
    call, so every control step is an observation a vision policy would get): observations per
    second per worker (target >= 50);
and the harness's overhead against bare env stepping: the same number of control steps through
`RoboFollowEnv.step` (which renders the three cameras every step) in one process; plus peak
memory per worker.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import robofollow  # noqa: F401  (first: it sets MUJOCO_GL before mujoco loads)
from robofollow import release
from robofollow.cli.common import positive
from robofollow.eval.policies.reference import ExpertPolicy
from robofollow.eval.running.deadline import DEFAULT_POLICY_TIMEOUT
from robofollow.eval.running.runner import EvalOptions, evaluate, read_results
from robofollow.sim.env import RoboFollowEnv

HERE = Path(__file__).resolve().parent


class SeeingExpert(ExpertPolicy):
    """The expert, asking for images and returning one action per call."""
    uses = frozenset({"state", "instruction", "images", "privileged"})
    chunk = 1


def seeing() -> SeeingExpert:
    return SeeingExpert()


def _sample(count: int) -> list[str]:
    """`count` episode ids of the current release, spread over its L0 round-1 episodes."""
    episodes = [episode_id for episode_id in release.benchmark().select(level="L0")
                if episode_id.partition("#r")[2] == "1"]
    return episodes[::max(1, len(episodes) // count)][:count]


def _child(policy: str, episode_ids: list[str], workers: int, queue) -> None:
    compiled = release.benchmark()  # the current release, as `robofollow eval` reads it
    tasks = tuple(episode_id.partition("#")[0] for episode_id in episode_ids)
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "run"
        # the options `robofollow eval --tasks ... --levels L0 --rounds 1` gives the runner
        options = EvalOptions(policy, tuple(compiled.spec.scenes), ("L0",), 1, "normal", "none",
                              compiled.spec.digest, tasks, policy_timeout=DEFAULT_POLICY_TIMEOUT,
                              release=compiled.release, release_digest=compiled.release_digest)
        began = time.perf_counter()
        evaluate(compiled, out, options, workers, progress=False)
        seconds = time.perf_counter() - began
        records = read_results(out / "episodes.jsonl")
    queue.put({"seconds": seconds, "episodes": len(records),
               "steps": sum(r["steps"] for r in records),
               "queries": sum(r["queries"] for r in records),
               "intent": float(np.mean([r["intent_score"] for r in records])),
               "peak_mb_self": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
               "peak_mb_workers": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024})


def timed(policy: str, episode_ids: list[str], workers: int) -> dict:
    context = multiprocessing.get_context("spawn")
    queue = context.Queue()
    process = context.Process(target=_child, args=(policy, episode_ids, workers, queue))
    process.start()
    result = queue.get()
    process.join()
    return result


def bare_env_seconds(episode_id: str, steps: int) -> float:
    env = RoboFollowEnv(episode=episode_id)
    env.reset()
    action = env.trajectory().action[0]
    began = time.perf_counter()
    for _ in range(steps):
        env.step(action)
    seconds = time.perf_counter() - began
    env.close()
    return seconds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=positive, default=3)
    parser.add_argument("--episodes", type=positive, default=16, help="episodes for `seeing`")
    parser.add_argument("--expert-episodes", type=positive, default=64,
                        help="episodes for the image-free `expert`")
    parser.add_argument("--policies", default="expert,seeing",
                        help="which of expert, seeing to time (default: both)")
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args(argv)
    chosen = [label for label in args.policies.split(",") if label]
    unknown = [label for label in chosen if label not in ("expert", "seeing")]
    if unknown or not chosen:
        parser.error(f"--policies {args.policies!r}: expected expert and/or seeing")
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HERE),
                                                             os.environ.get("PYTHONPATH")]))
    sys.path.insert(0, str(HERE))
    samples = {"expert": _sample(args.expert_episodes), "seeing": _sample(args.episodes)}
    figures: dict = {"episodes": {label: samples[label] for label in chosen}}
    print(f"episodes (L0, round 1, spread over the scenes): "
          f"{', '.join(f'{len(samples[label])} for {label}' for label in chosen)}; "
          f"{args.runs} runs per setting")
    for policy, label in (("expert", "expert"), ("eval_bench:seeing", "seeing")):
        if label not in chosen:
            continue
        episode_ids = samples[label]
        for workers in (1, 2):
            runs = [timed(policy, episode_ids, workers) for _ in range(args.runs)]
            seconds = statistics.median(r["seconds"] for r in runs)
            first = runs[0]
            peak = max(r["peak_mb_self" if workers == 1 else "peak_mb_workers"] for r in runs)
            figures[f"{label}_{workers}"] = {
                "seconds": seconds, "episodes_per_min": first["episodes"] / seconds * 60,
                "observations_per_s_per_worker": first["queries"] / seconds / workers,
                "steps": first["steps"], "queries": first["queries"],
                "mean_intent": first["intent"], "peak_mb_per_worker": peak}
            print(f"{label:7} {workers} worker(s): {first['episodes'] / seconds * 60:6.1f} "
                  f"episodes/min, {first['queries'] / seconds / workers:6.1f} observations/s "
                  f"per worker, mean Intent {first['intent']:.2f}, peak {peak:.0f} MB/worker")
    if "seeing" not in chosen:
        _write(args.json, figures)
        return 0
    episode_ids = samples["seeing"]
    steps = figures["seeing_1"]["steps"]
    bare = statistics.median(bare_env_seconds(episode_ids[0], steps // len(episode_ids))
                             * len(episode_ids) for _ in range(args.runs))
    overhead = figures["seeing_1"]["seconds"] / bare
    figures["bare_env_seconds"], figures["overhead_vs_env"] = bare, overhead
    print(f"bare env stepping (3 cameras every step), same {steps} steps: {bare:.1f} s -> the "
          f"harness with a seeing policy costs {overhead:.2f}x")
    _write(args.json, figures)
    return 0


def _write(path: str | None, figures: dict) -> None:
    if path:
        Path(path).write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    raise SystemExit(main())
