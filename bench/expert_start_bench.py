"""Start-up of `robofollow expert --episode ID` on a warm compiled-benchmark cache: a fresh
process from its start until the expert begins the episode (the command line parsed, the
benchmark read from the cache, the episode found; target under 2 s), beside a bare Python
start for scale.

    python bench/expert_start_bench.py [--runs 5] [--episode 'scene1/L0/...#r1']

The cache folder is temporary (ROBOFOLLOW_CACHE_DIR); the user's cache is not touched.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = 2.0  # s, median on a quiet machine

# the expert command, stopped where the simulation would begin
CHILD = """
import sys
from robofollow.sim import rollout

def begin(*args, **kwargs):
    raise SystemExit(0)

rollout.run_expert = begin
from robofollow.cli import main
sys.exit(main(["expert", "--episode", sys.argv[1], "--specs", sys.argv[2]]))
"""


def started(command: list[str], env: dict[str, str]) -> float:
    """Wall time of one process to its exit."""
    began = time.perf_counter()
    subprocess.run(command, env=env, check=True, capture_output=True)
    return time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--episode", default="scene1/L0/pickup_yellow_block_2#r1")
    parser.add_argument("--specs", type=Path, default=ROOT / "specs")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "ROBOFOLLOW_CACHE_DIR": cache}
        env.pop("ROBOFOLLOW_NO_CACHE", None)
        expert = [sys.executable, "-c", CHILD, args.episode, str(args.specs)]
        started(expert, env)  # fills the cache
        times = [started(expert, env) for _ in range(args.runs)]
        bare = [started([sys.executable, "-c", "pass"], env) for _ in range(args.runs)]
    print(f"expert start on a warm cache: median {statistics.median(times):.2f} s over "
          f"{args.runs} runs (target < {TARGET} s); a bare Python start: "
          f"{statistics.median(bare):.2f} s")


if __name__ == "__main__":
    main()
