"""Training throughput and peak memory of each learned baseline on this machine's CPU.

    python bench/train_bench.py [--runs 3] [--steps 30] [--cameras cam_high] [--factor 4]
                                [--kinds text,blind,form]

Each baseline (text, blind, form) is measured in its own process, pinned to one core and then
on all of them (XLA gains little from a second core, so two trainings side by side use a
2-core machine fully): synthetic demonstrations of
the dataset's shape (80 episodes of 150 frames, camera frames shrunk by --factor), one compiled
training step (batch 64) timed over --steps steps after a warm-up, --runs times. Reports the
median samples/s, samples/s per core, peak resident memory of the process, and the time of one
NumPy inference call (what `robofollow eval` pays per query). Needs robofollow[train].
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

from robofollow.cli.common import positive
from robofollow.learn.options import KINDS, reads_objects
from robofollow.sim.cameras import CAMERA_NAMES

EPISODES, LENGTH = 80, 150
IMAGE_KINDS = tuple(kind for kind in KINDS if not reads_objects(kind))  # what is synthesised


def synthetic(cameras: tuple[str, ...], factor: int):
    from robofollow.learn.demos import Demonstrations

    rng = np.random.default_rng(0)
    frames = EPISODES * LENGTH
    height, width = 240 // factor, 320 // factor
    words = ["pick up the left cube", "pick up the red cylinder", "push the right cube"]
    return Demonstrations(
        states=rng.standard_normal((frames, 14)).astype(np.float32),
        actions=rng.standard_normal((frames, 14)).astype(np.float32),
        starts=np.arange(EPISODES, dtype=np.int64) * LENGTH,
        lengths=np.full(EPISODES, LENGTH, np.int64),
        instructions=[f"Use your left arm to {words[e % 3]}." for e in range(EPISODES)],
        labels=[f"task{e % 16}" for e in range(EPISODES)],
        images={c: rng.integers(0, 256, (frames, height, width, 3), dtype=np.uint8)
                for c in cameras})


def measure(kind: str, cameras: tuple[str, ...], factor: int, steps: int, runs: int) -> dict:
    from robofollow.learn.model import Architecture, forward, init
    from robofollow.learn.train import Batches, TrainOptions, arrange, compiled_steps

    options = TrainOptions(dataset="synthetic", kind=kind, cameras=cameras, factor=factor)
    prepared = arrange(synthetic(cameras, factor), options)
    # the network and its start, as `train` makes them for these options
    arch = Architecture(options.kind, cameras, prepared.demos.images[cameras[0]].shape[1:3],
                        len(prepared.vocab), chunk=options.chunk)
    params = init(arch, options.seed)
    moments = tuple({k: np.zeros_like(v) for k, v in params.items()} for _ in range(2))
    step, _ = compiled_steps(arch, options, 10 * steps * runs)
    batches = Batches(prepared, options)
    params, moments, value = step(params, moments, batches.batch(0), 0)  # compile
    float(value)
    rates, number = [], 1
    for _ in range(runs):
        inputs = [batches.batch(number + i) for i in range(steps)]
        began = time.perf_counter()
        for batch in inputs:
            params, moments, value = step(params, moments, batch, number)
            number += 1
        float(value)
        rates.append(steps * options.batch / (time.perf_counter() - began))
    one = batches.batch(0)
    single = {c: one["images"][c][:1] for c in cameras}
    numpy_params = {k: np.asarray(v) for k, v in params.items()}
    calls = []
    for _ in range(20):
        began = time.perf_counter()
        forward(numpy_params, arch, single, one["state"][:1], one["tokens"][:1])
        calls.append(time.perf_counter() - began)
    cores = len(os.sched_getaffinity(0))
    rate = statistics.median(rates)
    return {"kind": kind, "samples_per_s": round(rate, 1),
            "samples_per_s_per_core": round(rate / cores, 1), "cores": cores,
            "peak_memory_mib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
            "inference_ms": round(1000 * statistics.median(calls), 1),
            "parameters": int(sum(v.size for v in numpy_params.values()))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=positive, default=3)
    parser.add_argument("--steps", type=positive, default=30)
    parser.add_argument("--cameras", default="cam_high")
    parser.add_argument("--factor", type=positive, default=4)
    parser.add_argument("--kinds", default=",".join(IMAGE_KINDS))
    parser.add_argument("--one", help=argparse.SUPPRESS)  # measure one kind in this process
    parser.add_argument("--pin", type=int, help=argparse.SUPPRESS)  # on this many cores
    args = parser.parse_args()
    cameras = tuple(args.cameras.split(","))
    for option, names, known in (("--kinds", args.kinds.split(","), IMAGE_KINDS),
                                 ("--cameras", cameras, CAMERA_NAMES)):
        if not set(names) <= set(known):
            parser.error(f"{option} {','.join(names)}: expected some of {', '.join(known)}")
    if args.one:
        os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:args.pin])
        print(json.dumps(measure(args.one, cameras, args.factor, args.steps, args.runs)))
        return
    print(f"cameras {args.cameras}, images {320 // args.factor}x{240 // args.factor}, batch 64, "
          f"median of {args.runs} runs of {args.steps} steps")
    print(f"{'baseline':<8} {'cores':>5} {'samples/s':>10} {'per core':>9} {'peak MiB':>9} "
          f"{'act() ms':>9} {'params':>9}")
    for kind in args.kinds.split(","):
        for pin in sorted({1, len(os.sched_getaffinity(0))}):
            line = subprocess.run([sys.executable, __file__, "--one", kind, "--pin", str(pin),
                                   "--runs", str(args.runs), "--steps", str(args.steps),
                                   "--cameras", args.cameras, "--factor", str(args.factor)],
                                  check=True, capture_output=True, text=True).stdout
            r = json.loads(line.strip().splitlines()[-1])
            print(f"{kind:<8} {r['cores']:>5} {r['samples_per_s']:>10} "
                  f"{r['samples_per_s_per_core']:>9} {r['peak_memory_mib']:>9} "
                  f"{r['inference_ms']:>9} {r['parameters']:>9}")


if __name__ == "__main__":
    main()
