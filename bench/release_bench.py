"""The current release: its size in the package, how long loading it takes, and `eval`'s
start-up reading it against reading the working compile from a warm compile cache (what every
command read before releases), side by side.

    python bench/release_bench.py [--runs 5] [--json out.json]

- size: the release's files (already gzip-compressed, so the wheel adds about as much);
- load: `release.load` in a process that has loaded it before (the per-process cache cleared
  each time), and in a fresh process, beside that process's `import`; target: at most 0.3 s;
- eval start-up: `robofollow eval --policy noop` on one episode, in fresh processes, the
  release against `--specs` (the built-in specs, the compile cache warmed first), run in
  turns; the ratio is the median of release / working compile, pair by pair (target: at
  most 1).
Medians over --runs. The compile cache is a temporary folder; the user's is not touched.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from robofollow import release
from robofollow.cli.common import positive
from robofollow.resources import builtin_specs, releases_dir

TASK = "scene2/L0/pickup_left_cube"
LOAD = "import time; t = time.perf_counter(); from robofollow import release; " \
       "i = time.perf_counter(); release.load(); print(i - t, time.perf_counter() - i)"


def size() -> dict[str, int]:
    folder = releases_dir() / release.CURRENT
    return {path.name: path.stat().st_size for path in sorted(folder.iterdir())}


def load_in_process(runs: int) -> list[float]:
    times = []
    for _ in range(runs):
        release._load.cache_clear()
        began = time.perf_counter()
        release.load()
        times.append(time.perf_counter() - began)
    return times


def _run(command: list[str], env: dict) -> float:
    began = time.perf_counter()
    subprocess.run(command, env=env, check=True, capture_output=True)
    return time.perf_counter() - began


def eval_start(runs: int, cache: str) -> dict[str, list[float]]:
    """Fresh `robofollow eval` processes on one noop episode: the release, then the working
    compile of the built-in specs, in turns."""
    env = {**os.environ, "ROBOFOLLOW_CACHE_DIR": cache}
    env.pop("ROBOFOLLOW_NO_CACHE", None)
    times: dict[str, list[float]] = {"release": [], "working compile": []}
    with tempfile.TemporaryDirectory() as out:
        def command(name: str, extra: list[str]) -> list[str]:
            return [sys.executable, "-m", "robofollow.cli", "eval", "--policy", "noop",
                    "--tasks", TASK, "--rounds", "1", "--quiet", "--out",
                    str(Path(out) / f"{name}{len(times['release'])}"), *extra]

        subprocess.run(command("warm", ["--specs", str(builtin_specs())]), env=env,
                       check=True, capture_output=True)  # (fills the compile cache)
        for _ in range(runs):
            times["release"].append(_run(command("r", []), env))
            times["working compile"].append(
                _run(command("w", ["--specs", str(builtin_specs())]), env))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=positive, default=5)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args()
    files = size()
    in_process = load_in_process(args.runs)
    fresh = [[float(v) for v in subprocess.run([sys.executable, "-c", LOAD], check=True,
                                               capture_output=True, text=True).stdout.split()]
             for _ in range(args.runs)]
    with tempfile.TemporaryDirectory() as cache:
        started = eval_start(args.runs, cache)
    medians = {"load": statistics.median(in_process),
               "fresh process: import": statistics.median(i for i, _ in fresh),
               "fresh process: load": statistics.median(load for _, load in fresh),
               **{f"eval start, {k}": statistics.median(v) for k, v in started.items()}}
    ratio = statistics.median(r / w for r, w in zip(started["release"],
                                                     started["working compile"], strict=True))
    print(f"release {release.CURRENT}: " + ", ".join(f"{name} {count:,} bytes"
                                                   for name, count in files.items())
          + f" ({sum(files.values()) / 2 ** 20:.2f} MiB; target at most 1 MB)")
    for name, value in medians.items():
        print(f"{name:<28} {value:.3f} s (median of {args.runs})")
    print(f"eval start-up, release / working compile from a warm cache, paired: {ratio:.2f} "
          "(target at most 1)")
    if args.json:
        Path(args.json).write_text(json.dumps({"size": files, "medians": medians,
                                               "ratio": ratio}, indent=1) + "\n")


if __name__ == "__main__":
    main()
