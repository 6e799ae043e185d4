"""`robofollow expert --episode ID` on a warm compiled-benchmark cache, in fresh processes: the
start (command line parsed, benchmark read from the cache, episode found; target under 2 s) and
the whole command with its episode simulated and scored, beside a bare Python start for scale.

    python bench/expert_start_bench.py [--runs 5] [--episode ID --specs DIR]

By default the specs are the shipped ones with the scene family written from
docs/spec-language.md beside them (tests/data/authored_scene/scene6.rf), and the episode is
that scene's first: `scene6/L0/red_cube_on_purple_label#r1`. The cache folder is temporary
(ROBOFOLLOW_CACHE_DIR); the user's cache is not touched.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from robofollow.cli.common import positive

ROOT = Path(__file__).resolve().parent.parent
AUTHORED = ROOT / "tests" / "data" / "authored_scene" / "scene6.rf"
TARGET = 2.0  # s, median on a quiet machine

# the expert command, stopped where the simulation would begin
START = """
import sys
from robofollow.sim import rollout

def begin(*args, **kwargs):
    raise SystemExit(0)

rollout.run_expert = begin
from robofollow.cli import main
sys.exit(main(["expert", "--episode", sys.argv[1], "--specs", sys.argv[2]]))
"""


def wall(command: list[str], env: dict[str, str]) -> float:
    """Wall time of one process to its exit."""
    began = time.perf_counter()
    subprocess.run(command, env=env, check=True, capture_output=True)
    return time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=positive, default=5)
    parser.add_argument("--episode", default="scene6/L0/red_cube_on_purple_label#r1")
    parser.add_argument("--specs", type=Path,
                        help="spec folder (default: the shipped specs and the authored scene)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as root:
        env = {**os.environ, "ROBOFOLLOW_CACHE_DIR": os.path.join(root, "cache")}
        env.pop("ROBOFOLLOW_NO_CACHE", None)
        specs = args.specs
        if specs is None:
            specs = Path(shutil.copytree(ROOT / "specs", os.path.join(root, "specs")))
            shutil.copy(AUTHORED, specs)
        start = [sys.executable, "-c", START, args.episode, str(specs)]
        whole = [sys.executable, "-m", "robofollow.cli", "expert", "--episode", args.episode,
                 "--specs", str(specs)]
        wall(whole, env)  # fills the cache
        starts = [wall(start, env) for _ in range(args.runs)]
        wholes = [wall(whole, env) for _ in range(args.runs)]
        bare = [wall([sys.executable, "-c", "pass"], env) for _ in range(args.runs)]
    print(f"{args.episode} on a warm cache, median of {args.runs} fresh processes:")
    print(f"  start (to the first simulated step) {statistics.median(starts):5.2f} s  "
          f"(target < {TARGET} s)")
    print(f"  the whole command, episode included {statistics.median(wholes):5.2f} s")
    print(f"  a bare Python start                 {statistics.median(bare):5.2f} s")


if __name__ == "__main__":
    main()
